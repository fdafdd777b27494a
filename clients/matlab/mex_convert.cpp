// Frames, States and WorldInfos as Octave/MATLAB structs (mex_convert.h).
#include "mex_convert.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <vector>

#include "protocol/channels.h"

namespace sim4cv::mexbind {
namespace {

mxArray* Scalar(double value) { return mxCreateDoubleScalar(value); }

mxArray* Int64(int64_t value) {
  mxArray* out = mxCreateNumericMatrix(1, 1, mxINT64_CLASS, mxREAL);
  *static_cast<int64_t*>(mxGetData(out)) = value;
  return out;
}

mxArray* Row(std::initializer_list<double> values) {
  mxArray* out = mxCreateDoubleMatrix(1, values.size(), mxREAL);
  double* dst = static_cast<double*>(mxGetData(out));
  for (const double v : values) *dst++ = v;
  return out;
}

// An n x 1 struct array with these fields (0 x 1 when n is 0, fields kept).
mxArray* StructColumn(std::size_t n, const std::vector<const char*>& fields) {
  return mxCreateStructMatrix(n, 1, static_cast<int>(fields.size()), const_cast<const char**>(fields.data()));
}

std::string LowerSuffix(const std::string& enum_name, const std::string& prefix) {
  std::string out = enum_name.rfind(prefix, 0) == 0 ? enum_name.substr(prefix.size()) : enum_name;
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// The channel's name in the table (protocol/channels.h), a string literal there.
const char* ChannelField(proto::Channel channel) {
  const channels::ChannelInfo* info = channels::Find(channel);
  return info ? info->name.data() : nullptr;
}

// One pass over the pixels: C-order rows of `stride` bytes, pixel (c, r)
// component k, into MATLAB's column-major element (r, c, k), written in
// memory order (the reads stride down a column of the image, which stays in cache).
template <typename T>
mxArray* ImageArray(const proto::Image& image, uint32_t width, uint32_t height, mxClassID class_id) {
  const uint32_t components = std::max<uint32_t>(image.components(), 1);
  const std::size_t row_bytes = std::size_t(width) * components * sizeof(T);
  if (image.stride() < row_bytes ||
      image.data().size() < (height ? (height - 1) * std::size_t(image.stride()) + row_bytes : 0)) {
    throw ConnectionError("frame image of channel " + proto::Channel_Name(image.channel()) + " holds " +
                          std::to_string(image.data().size()) + " bytes, too few for " + std::to_string(width) + "x" +
                          std::to_string(height) + "x" + std::to_string(components));
  }
  const mwSize dims[3] = {height, width, components};
  mxArray* out = mxCreateNumericArray(components > 1 ? 3 : 2, dims, class_id, mxREAL);
  T* dst = static_cast<T*>(mxGetData(out));
  const std::size_t stride = image.stride();
  for (uint32_t k = 0; k < components; ++k) {
    for (uint32_t c = 0; c < width; ++c) {
      const char* src = image.data().data() + (std::size_t(c) * components + k) * sizeof(T);
      for (uint32_t r = 0; r < height; ++r, src += stride, ++dst) {
        if constexpr (sizeof(T) == 1) {
          *dst = static_cast<T>(*src);
        } else {
          std::memcpy(dst, src, sizeof(T));  // little-endian host, as the wire; no alignment assumed
        }
      }
    }
  }
  return out;
}

mxArray* ImageToArray(const proto::Image& image, uint32_t width, uint32_t height) {
  switch (image.element()) {
    case proto::ELEMENT_TYPE_U8:
      return ImageArray<uint8_t>(image, width, height, mxUINT8_CLASS);
    case proto::ELEMENT_TYPE_U16:
      return ImageArray<uint16_t>(image, width, height, mxUINT16_CLASS);
    case proto::ELEMENT_TYPE_F32:
      return ImageArray<float>(image, width, height, mxSINGLE_CLASS);
    default:
      throw ConnectionError("frame image of channel " + proto::Channel_Name(image.channel()) +
                            " has an unknown element type " + std::to_string(image.element()));
  }
}

mxArray* Boxes(const proto::Frame& frame) {
  mxArray* boxes = StructColumn(
      frame.boxes_size(), {"object_id", "object_class", "x", "y", "width", "height", "visibility", "visible_pixels"});
  for (int i = 0; i < frame.boxes_size(); ++i) {
    const proto::Box& b = frame.boxes(i);
    mxSetFieldByNumber(boxes, i, 0, Scalar(b.object_id()));
    mxSetFieldByNumber(boxes, i, 1, mxCreateString(ClassName(b.object_class()).c_str()));
    mxSetFieldByNumber(boxes, i, 2, Scalar(b.x()));
    mxSetFieldByNumber(boxes, i, 3, Scalar(b.y()));
    mxSetFieldByNumber(boxes, i, 4, Scalar(b.width()));
    mxSetFieldByNumber(boxes, i, 5, Scalar(b.height()));
    mxSetFieldByNumber(boxes, i, 6, Scalar(b.visibility()));
    mxSetFieldByNumber(boxes, i, 7, Scalar(b.visible_pixels()));
  }
  return boxes;
}

mxArray* Intrinsics(const proto::Frame& frame) {
  if (!frame.has_camera_intrinsics()) return mxCreateDoubleMatrix(0, 0, mxREAL);
  const proto::CameraIntrinsics& k = frame.camera_intrinsics();
  const char* fields[] = {"fx", "fy", "cx", "cy"};
  mxArray* out = mxCreateStructMatrix(1, 1, 4, fields);
  mxSetFieldByNumber(out, 0, 0, Scalar(k.fx()));
  mxSetFieldByNumber(out, 0, 1, Scalar(k.fy()));
  mxSetFieldByNumber(out, 0, 2, Scalar(k.cx()));
  mxSetFieldByNumber(out, 0, 3, Scalar(k.cy()));
  return out;
}

mxArray* CellStr(const google::protobuf::RepeatedPtrField<std::string>& strings) {
  mxArray* out = mxCreateCellMatrix(strings.size(), 1);
  for (int i = 0; i < strings.size(); ++i) mxSetCell(out, i, mxCreateString(strings.Get(i).c_str()));
  return out;
}

}  // namespace

std::string KindName(proto::EntityKind kind) { return LowerSuffix(proto::EntityKind_Name(kind), "ENTITY_KIND_"); }

std::string ClassName(proto::ObjectClass object_class) {
  return LowerSuffix(proto::ObjectClass_Name(object_class), "OBJECT_CLASS_");
}

mxArray* FrameToStruct(const proto::Frame& frame) {
  const char* fields[] = {"frame_id", "sim_time", "camera", "render_end_mono_ns", "width", "height", "dropped_frames"};
  mxArray* out = mxCreateStructMatrix(1, 1, 7, fields);
  mxSetFieldByNumber(out, 0, 0, Scalar(static_cast<double>(frame.frame_id())));
  mxSetFieldByNumber(out, 0, 1, Scalar(frame.sim_time()));
  mxSetFieldByNumber(out, 0, 2, mxCreateString(frame.camera().c_str()));
  mxSetFieldByNumber(out, 0, 3, Int64(frame.render_end_mono_ns()));
  mxSetFieldByNumber(out, 0, 4, Scalar(frame.width()));
  mxSetFieldByNumber(out, 0, 5, Scalar(frame.height()));
  mxSetFieldByNumber(out, 0, 6, Scalar(static_cast<double>(frame.dropped_frames())));
  for (const proto::Image& image : frame.images()) {
    const char* known = ChannelField(image.channel());
    const std::string name = known ? known : "channel_" + std::to_string(image.channel());
    const int field = mxAddField(out, name.c_str());
    mxSetFieldByNumber(out, 0, field, ImageToArray(image, frame.width(), frame.height()));
  }
  mxSetFieldByNumber(out, 0, mxAddField(out, "boxes"), Boxes(frame));
  mxSetFieldByNumber(out, 0, mxAddField(out, "intrinsics"), Intrinsics(frame));
  return out;
}

mxArray* StateToStruct(const proto::State& state) {
  const char* fields[] = {"frame_id", "sim_time", "entities", "last_tracker_output"};
  mxArray* out = mxCreateStructMatrix(1, 1, 4, fields);
  mxSetFieldByNumber(out, 0, 0, Scalar(static_cast<double>(state.frame_id())));
  mxSetFieldByNumber(out, 0, 1, Scalar(state.sim_time()));
  mxArray* entities =
      StructColumn(state.entities_size(), {"id", "name", "kind", "position", "yaw", "orientation", "velocity"});
  for (int i = 0; i < state.entities_size(); ++i) {
    const proto::EntityState& e = state.entities(i);
    const proto::Quaternion& q = e.orientation();
    const double yaw = std::atan2(2 * (q.w() * q.z() + q.x() * q.y()), 1 - 2 * (q.y() * q.y() + q.z() * q.z()));
    mxSetFieldByNumber(entities, i, 0, Scalar(e.id()));
    mxSetFieldByNumber(entities, i, 1, mxCreateString(e.name().c_str()));
    mxSetFieldByNumber(entities, i, 2, mxCreateString(KindName(e.kind()).c_str()));
    mxSetFieldByNumber(entities, i, 3, Row({e.position().x(), e.position().y(), e.position().z()}));
    mxSetFieldByNumber(entities, i, 4, Scalar(yaw * 180.0 / M_PI));
    mxSetFieldByNumber(entities, i, 5, Row({q.w(), q.x(), q.y(), q.z()}));
    mxSetFieldByNumber(entities, i, 6,
                       Row({e.linear_velocity().x(), e.linear_velocity().y(), e.linear_velocity().z()}));
  }
  mxSetFieldByNumber(out, 0, 2, entities);
  const proto::TrackerOutput& t = state.last_tracker_output();
  const char* output_fields[] = {"frame_id", "box", "confidence"};
  mxArray* output = mxCreateStructMatrix(1, 1, 3, output_fields);
  mxSetFieldByNumber(output, 0, 0, Scalar(static_cast<double>(t.frame_id())));
  mxSetFieldByNumber(output, 0, 1, Row({t.box().x(), t.box().y(), t.box().width(), t.box().height()}));
  mxSetFieldByNumber(output, 0, 2, Scalar(t.confidence()));
  mxSetFieldByNumber(out, 0, 3, output);
  return out;
}

mxArray* WorldToStruct(const proto::WorldInfo& world) {
  const char* fields[] = {"scene_name", "frame_id", "entities", "cameras", "routes"};
  mxArray* out = mxCreateStructMatrix(1, 1, 5, fields);
  mxSetFieldByNumber(out, 0, 0, mxCreateString(world.scene_name().c_str()));
  mxSetFieldByNumber(out, 0, 1, Scalar(static_cast<double>(world.frame_id())));
  mxArray* entities = StructColumn(world.entities_size(), {"id", "name", "kind"});
  for (int i = 0; i < world.entities_size(); ++i) {
    mxSetFieldByNumber(entities, i, 0, Scalar(world.entities(i).id()));
    mxSetFieldByNumber(entities, i, 1, mxCreateString(world.entities(i).name().c_str()));
    mxSetFieldByNumber(entities, i, 2, mxCreateString(KindName(world.entities(i).kind()).c_str()));
  }
  mxSetFieldByNumber(out, 0, 2, entities);
  mxArray* cameras = StructColumn(world.cameras_size(), {"name", "width", "height", "fov_y_deg", "mounted_on"});
  for (int i = 0; i < world.cameras_size(); ++i) {
    const proto::CameraInfo& c = world.cameras(i);
    mxSetFieldByNumber(cameras, i, 0, mxCreateString(c.name().c_str()));
    mxSetFieldByNumber(cameras, i, 1, Scalar(c.width()));
    mxSetFieldByNumber(cameras, i, 2, Scalar(c.height()));
    mxSetFieldByNumber(cameras, i, 3, Scalar(c.fov_y_deg()));
    mxSetFieldByNumber(cameras, i, 4, mxCreateString(c.mounted_on().c_str()));
  }
  mxSetFieldByNumber(out, 0, 3, cameras);
  mxSetFieldByNumber(out, 0, 4, CellStr(world.routes()));
  return out;
}

}  // namespace sim4cv::mexbind
