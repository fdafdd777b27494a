#include "driving/waypoint_model.h"

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string_view>
#include <vector>

namespace sim4cv::driving {
namespace {

// OpenCV 4.6's DNN does not report an ONNX model's input shapes, so the
// graph's declared inputs and outputs are read from the file itself: a
// minimal reader of the protobuf wire format for the few fields of onnx.proto
// needed (ModelProto.graph 7; GraphProto.initializer 5, input 11, output 12;
// TensorProto.name 8; ValueInfoProto.name 1, type 2; TypeProto.tensor_type 1;
// Tensor.elem_type 1, shape 2; TensorShapeProto.dim 1; Dimension.dim_value 1).
struct TensorInfo {
  std::string name;
  int elem_type = 0;          // 1: float32
  std::vector<int64_t> dims;  // -1: symbolic or unknown
};

struct Field {
  uint32_t number = 0;
  uint32_t wire_type = 0;
  uint64_t value = 0;      // varint fields
  std::string_view bytes;  // length-delimited fields
};

class WireReader {
 public:
  explicit WireReader(std::string_view data) : data_(data) {}

  // The next field, or false at the end. Throws std::runtime_error on bytes
  // that are not protobuf.
  bool Next(Field& field) {
    if (pos_ >= data_.size()) return false;
    const uint64_t key = Varint();
    field.number = static_cast<uint32_t>(key >> 3);
    field.wire_type = static_cast<uint32_t>(key & 7);
    switch (field.wire_type) {
      case 0:
        field.value = Varint();
        return true;
      case 1:
        return Skip(8);
      case 2: {
        const uint64_t size = Varint();
        if (size > data_.size() - pos_) throw std::runtime_error("a field runs past the end");
        field.bytes = data_.substr(pos_, size);
        pos_ += size;
        return true;
      }
      case 5:
        return Skip(4);
      default:
        throw std::runtime_error("wire type " + std::to_string(field.wire_type) + " at byte " + std::to_string(pos_));
    }
  }

 private:
  uint64_t Varint() {
    uint64_t value = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      if (pos_ >= data_.size()) throw std::runtime_error("truncated varint");
      const auto byte = static_cast<uint8_t>(data_[pos_++]);
      value |= static_cast<uint64_t>(byte & 0x7f) << shift;
      if (!(byte & 0x80)) return value;
    }
    throw std::runtime_error("varint too long");
  }
  bool Skip(std::size_t n) {
    if (n > data_.size() - pos_) throw std::runtime_error("a field runs past the end");
    pos_ += n;
    return true;
  }

  std::string_view data_;
  std::size_t pos_ = 0;
};

TensorInfo ReadValueInfo(std::string_view bytes) {
  TensorInfo info;
  Field f, t, tensor, shape, dim;
  for (WireReader value_info(bytes); value_info.Next(f);) {
    if (f.number == 1 && f.wire_type == 2) info.name = std::string(f.bytes);
    if (f.number != 2 || f.wire_type != 2) continue;  // TypeProto
    for (WireReader type(f.bytes); type.Next(t);) {
      if (t.number != 1 || t.wire_type != 2) continue;  // tensor_type
      for (WireReader tensor_type(t.bytes); tensor_type.Next(tensor);) {
        if (tensor.number == 1 && tensor.wire_type == 0) info.elem_type = static_cast<int>(tensor.value);
        if (tensor.number != 2 || tensor.wire_type != 2) continue;  // shape
        for (WireReader dims(tensor.bytes); dims.Next(shape);) {
          if (shape.number != 1 || shape.wire_type != 2) continue;  // dim
          int64_t size = -1;
          for (WireReader dimension(shape.bytes); dimension.Next(dim);) {
            if (dim.number == 1 && dim.wire_type == 0) size = static_cast<int64_t>(dim.value);
          }
          info.dims.push_back(size);
        }
      }
    }
  }
  return info;
}

// The graph's inputs (initializers listed as inputs left out) and outputs.
void ReadSignature(std::string_view model, std::vector<TensorInfo>& inputs, std::vector<TensorInfo>& outputs) {
  Field f, g, t;
  bool has_graph = false;
  std::set<std::string> initializers;
  std::vector<TensorInfo> declared;
  for (WireReader reader(model); reader.Next(f);) {
    if (f.number != 7 || f.wire_type != 2) continue;
    has_graph = true;
    for (WireReader graph(f.bytes); graph.Next(g);) {
      if (g.wire_type != 2) continue;
      if (g.number == 11) declared.push_back(ReadValueInfo(g.bytes));
      if (g.number == 12) outputs.push_back(ReadValueInfo(g.bytes));
      if (g.number == 5) {
        for (WireReader tensor(g.bytes); tensor.Next(t);) {
          if (t.number == 8 && t.wire_type == 2) initializers.insert(std::string(t.bytes));
        }
      }
    }
  }
  if (!has_graph) throw std::runtime_error("no graph");
  for (auto& input : declared) {
    if (!initializers.count(input.name)) inputs.push_back(std::move(input));
  }
}

std::string Shape(const std::vector<int64_t>& dims) {
  std::string text = "[";
  for (std::size_t i = 0; i < dims.size(); ++i) {
    text += (i ? ", " : "") + (dims[i] < 0 ? std::string("?") : std::to_string(dims[i]));
  }
  return text + "]";
}

std::string List(const std::vector<TensorInfo>& tensors) {
  std::string text;
  for (const auto& t : tensors) text += (text.empty() ? "" : ", ") + t.name + " " + Shape(t.dims);
  return text.empty() ? "none" : text;
}

const TensorInfo* Find(const std::vector<TensorInfo>& tensors, const std::string& name) {
  for (const auto& t : tensors) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

}  // namespace

WaypointModel::WaypointModel(const std::string& path) : path_(path) {
  const std::string where = "WaypointModel: '" + path + "'";
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelError("WaypointModel: cannot read the model file '" + path + "': " + std::strerror(errno));
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<TensorInfo> inputs, outputs;
  try {
    ReadSignature(bytes, inputs, outputs);
  } catch (const std::runtime_error& e) {
    throw ModelError(where + " is not an ONNX model (" + e.what() + ")");
  }
  const std::string contract =
      " (the contract: inputs image [1, 3, H, W] and, optionally, goal [1, 1]; output waypoints [1, 8])";

  const TensorInfo* image = Find(inputs, kImageInput);
  if (!image) throw ModelError(where + " has no input 'image'; its inputs: " + List(inputs) + contract);
  const auto& d = image->dims;
  if (d.size() != 4 || d[0] != 1 || d[1] != 3 || d[2] <= 0 || d[3] <= 0) {
    throw ModelError(where + ": input 'image' is " + Shape(d) +
                     "; expected [1, 3, H, W] (3 channels, RGB; fixed H and W)");
  }
  height_ = static_cast<int>(d[2]);
  width_ = static_cast<int>(d[3]);
  for (const auto& input : inputs) {
    if (input.name == kImageInput) continue;
    if (input.name != kGoalInput) {
      throw ModelError(where + " has an unexpected input '" + input.name + "' " + Shape(input.dims) + contract);
    }
    if (input.dims != std::vector<int64_t>{1, 1}) {
      throw ModelError(where + ": input 'goal' is " + Shape(input.dims) + "; expected [1, 1]");
    }
    has_goal_ = true;
  }
  for (const auto& input : inputs) {
    if (input.elem_type != 1) {
      throw ModelError(where + ": input '" + input.name + "' has ONNX element type " + std::to_string(input.elem_type) +
                       "; expected 1 (float32)");
    }
  }
  const TensorInfo* output = Find(outputs, kOutput);
  if (!output) throw ModelError(where + " has no output 'waypoints'; its outputs: " + List(outputs) + contract);
  if (output->dims != std::vector<int64_t>{1, 8}) {
    throw ModelError(where + ": output 'waypoints' is " + Shape(output->dims) +
                     "; expected [1, 8] (v1 h1 v2 h2 v3 h3 v4 h4)");
  }

  try {
    net_ = cv::dnn::readNetFromONNX(path);
  } catch (const cv::Exception& e) {
    throw ModelError(where + ": OpenCV's DNN cannot load it: " + e.what());
  }
  net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  goal_blob_ = cv::Mat(std::vector<int>{1, 1}, CV_32F, cv::Scalar(0));
  // The dry run: the whole graph once on a black image.
  cv::Mat blob(std::vector<int>{1, 3, height_, width_}, CV_32F, cv::Scalar(0));
  cv::Mat result;
  try {
    net_.setInput(blob, kImageInput);
    if (has_goal_) net_.setInput(goal_blob_, kGoalInput);
    result = net_.forward(kOutput);
  } catch (const cv::Exception& e) {
    throw ModelError(where + ": OpenCV's DNN cannot run it on a [1, 3, " + std::to_string(height_) + ", " +
                     std::to_string(width_) + "] image: " + e.what());
  }
  if (result.total() != 8) {
    throw ModelError(where + ": a dry run gave " + std::to_string(result.total()) + " numbers; expected 8");
  }
}

Waypoints WaypointModel::Predict(const cv::Mat& rgb, float goal) {
  if (rgb.empty() || rgb.type() != CV_8UC3) {
    throw std::invalid_argument("WaypointModel::Predict: expected an 8-bit 3-channel RGB image, got type " +
                                std::to_string(rgb.type()) + " of " + std::to_string(rgb.cols) + "x" +
                                std::to_string(rgb.rows));
  }
  if (rgb.cols == width_ && rgb.rows == height_) return Run(rgb, goal);
  cv::resize(rgb, resized_, cv::Size(width_, height_), 0, 0, cv::INTER_AREA);
  return Run(resized_, goal);
}

Waypoints WaypointModel::Run(const cv::Mat& rgb, float goal) {
  // HWC uint8 -> 1 x 3 x H x W float32, channels in the order given (RGB):
  // no scaling, no mean, no swap; the model normalises.
  const cv::Mat blob = cv::dnn::blobFromImage(rgb, 1.0, cv::Size(), cv::Scalar(), false, false, CV_32F);
  net_.setInput(blob, kImageInput);
  if (has_goal_) {
    goal_blob_.at<float>(0) = goal;
    net_.setInput(goal_blob_, kGoalInput);
  }
  const cv::Mat out = net_.forward(kOutput);
  Waypoints waypoints{};
  const cv::Mat flat = out.reshape(1, 1);
  for (int i = 0; i < 8; ++i) waypoints[static_cast<std::size_t>(i)] = flat.at<float>(0, i);
  return waypoints;
}

}  // namespace sim4cv::driving
