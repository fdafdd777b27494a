// Unit tests of the zero-copy Frame encoder (server/transport/frame_encoding.*):
// the concatenated segments must parse as the Envelope protobuf would write.
#include "server/transport/frame_encoding.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "protocol/framing.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::transport {
namespace {

constexpr uint32_t kWidth = 7;
constexpr uint32_t kHeight = 5;

class FrameEncodingTest : public ::testing::Test {
 protected:
  FrameEncodingTest() {
    frame_ = pool_.Acquire(&writable_);
    FillFrame(*writable_, kWidth, kHeight);
  }

  static void FillFrame(session::Frame& f, uint32_t width, uint32_t height) {
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    f.frame_id = 1234567890123ull;
    f.sim_time = 41.125;
    f.camera_index = 0;
    f.width = width;
    f.height = height;
    f.render_end_mono_ns = -42;  // any int64 survives
    const auto rgb = f.Hold(proto::CHANNEL_RGB);
    for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(i * 7 + 3);
    const auto depth = f.Hold<float>(proto::CHANNEL_DEPTH);
    for (std::size_t i = 0; i < pixels; ++i) depth[i] = 0.5f + static_cast<float>(i) * 1.25f;
    depth[pixels - 1] = std::numeric_limits<float>::infinity();
    const auto mask = f.Hold<uint16_t>(proto::CHANNEL_MASK);
    for (std::size_t i = 0; i < pixels; ++i) mask[i] = static_cast<uint16_t>(i % 3 == 0 ? 0 : 100 + i * 517);
    f.boxes.clear();
    render::GroundTruthBox car;
    car.instance = 1;
    car.object_class = proto::OBJECT_CLASS_CAR;
    car.x = 1;
    car.y = 2;
    car.width = 3;
    car.height = 2;
    car.visible_pixels = 5;
    car.visibility = 0.75f;
    render::GroundTruthBox building;
    building.instance = 101;
    building.object_class = proto::OBJECT_CLASS_BUILDING;
    building.x = 0;
    building.y = 0;
    building.width = width;
    building.height = 1;
    building.visible_pixels = width;
    building.visibility = 1.0f;
    f.boxes = {car, building};
    f.intrinsics = {155.5, 155.25, 160.0, 90.0, width, height, {}};
    f.camera_pose.position = {1.5, -2.0, 16.0};
    f.camera_pose.orientation = Eigen::Quaterniond(0.5, -0.5, 0.5, -0.5);
    const Eigen::Vector3d at_rest = Eigen::Vector3d::Zero();
    f.objects = {{1, proto::OBJECT_CLASS_CAR, {10.0, 20.0, 0.75}, {0.0, 0.0, 0.0, 1.0}, {-6.0, 0.25, 0.0},
                  {0.0, 0.0, 0.125}, {2.25, 0.9, 0.6}, {0.5f, 1.5f, 3.25f, 2.75f}, true},
                 // In view but occluded: no Box.
                 {102, proto::OBJECT_CLASS_BUILDING, {-20.0, 5.0, 3.5}, {1.0, 0.0, 0.0, 0.0}, at_rest, at_rest,
                  {5.0, 4.0, 3.5}, {0.0f, 0.0f, 2.0f, 1.0f}, false}};
    f.state.Clear();
    f.state.set_frame_id(f.frame_id);
    f.state.set_sim_time(f.sim_time);
    proto::EntityState* e = f.state.add_entities();
    e->set_id(1);
    e->set_name("car");
    e->set_kind(proto::ENTITY_KIND_CAR);
    e->mutable_position()->set_x(-12.5);
  }

  static proto::Subscribed Subscription(std::vector<proto::Channel> channels) {
    proto::Subscribed s;
    s.set_camera("uav");
    for (auto c : channels) s.add_channels(c);
    s.set_delivery(proto::DELIVERY_NEWEST);
    return s;
  }

  // The encoder's segments, concatenated.
  std::string Concatenate() const {
    std::string bytes;
    for (const Segment& s : encoder_.segments()) bytes.append(reinterpret_cast<const char*>(s.data), s.size);
    return bytes;
  }

  // Encodes, checks size and prefix, and parses the envelope.
  proto::Envelope EncodeAndParse(const std::vector<proto::Channel>& channels, bool with_state, uint64_t dropped,
                                 bool length_prefix) {
    encoder_.Encode(*frame_, "uav", Subscription(channels), with_state, dropped, length_prefix);
    std::string bytes = Concatenate();
    EXPECT_EQ(bytes.size(), encoder_.total_size());
    if (length_prefix) {
      EXPECT_GE(bytes.size(), wire::kLengthPrefixBytes);
      const uint32_t prefix = wire::DecodeLengthPrefix(reinterpret_cast<const uint8_t*>(bytes.data()));
      EXPECT_EQ(prefix, bytes.size() - wire::kLengthPrefixBytes);
      bytes.erase(0, wire::kLengthPrefixBytes);
    }
    proto::Envelope envelope;
    EXPECT_TRUE(envelope.ParseFromString(bytes));
    EXPECT_TRUE(envelope.has_frame());
    // What protobuf itself would write for the same message has the same size.
    EXPECT_EQ(envelope.ByteSizeLong(), bytes.size());
    return envelope;
  }

  void ExpectMeta(const proto::Frame& f, uint64_t dropped) const {
    EXPECT_EQ(f.frame_id(), frame_->frame_id);
    EXPECT_DOUBLE_EQ(f.sim_time(), frame_->sim_time);
    EXPECT_EQ(f.camera(), "uav");
    EXPECT_EQ(f.width(), frame_->width);
    EXPECT_EQ(f.height(), frame_->height);
    EXPECT_EQ(f.dropped_frames(), dropped);
    EXPECT_EQ(f.render_end_mono_ns(), frame_->render_end_mono_ns);
  }

  void ExpectImage(const proto::Image& image, proto::Channel channel) const {
    EXPECT_EQ(image.channel(), channel);
    const std::size_t pixels = static_cast<std::size_t>(frame_->width) * frame_->height;
    switch (channel) {
      case proto::CHANNEL_RGB:
        EXPECT_EQ(image.format(), proto::PIXEL_FORMAT_RGB8);
        EXPECT_EQ(image.stride(), frame_->width * 3);
        ASSERT_EQ(image.data().size(), pixels * 3);
        EXPECT_EQ(0, std::memcmp(image.data().data(), frame_->Pixels(proto::CHANNEL_RGB), pixels * 3));
        break;
      case proto::CHANNEL_DEPTH: {
        EXPECT_EQ(image.format(), proto::PIXEL_FORMAT_DEPTH_F32);
        EXPECT_EQ(image.stride(), frame_->width * 4);
        ASSERT_EQ(image.data().size(), pixels * 4);
        std::vector<float> depth(pixels);
        std::memcpy(depth.data(), image.data().data(), pixels * 4);
        EXPECT_TRUE(std::ranges::equal(depth, frame_->Plane<float>(proto::CHANNEL_DEPTH)));
        break;
      }
      case proto::CHANNEL_MASK: {
        EXPECT_EQ(image.format(), proto::PIXEL_FORMAT_INSTANCE_U16);
        EXPECT_EQ(image.stride(), frame_->width * 2);
        ASSERT_EQ(image.data().size(), pixels * 2);
        // Little-endian on the wire.
        for (std::size_t i = 0; i < pixels; ++i) {
          const auto lo = static_cast<uint8_t>(image.data()[2 * i]);
          const auto hi = static_cast<uint8_t>(image.data()[2 * i + 1]);
          ASSERT_EQ(static_cast<uint16_t>(lo | (hi << 8)), frame_->Plane<uint16_t>(proto::CHANNEL_MASK)[i]) << "pixel " << i;
        }
        break;
      }
      default: ADD_FAILURE() << "unexpected channel " << channel;
    }
  }

  void ExpectBoxes(const proto::Frame& f) const {
    ASSERT_EQ(f.boxes_size(), 2);
    const proto::Box& car = f.boxes(0);
    EXPECT_EQ(car.object_id(), 1u);
    EXPECT_EQ(car.object_class(), proto::OBJECT_CLASS_CAR);
    EXPECT_EQ(car.x(), 1u);
    EXPECT_EQ(car.y(), 2u);
    EXPECT_EQ(car.width(), 3u);
    EXPECT_EQ(car.height(), 2u);
    EXPECT_EQ(car.visible_pixels(), 5u);
    EXPECT_FLOAT_EQ(car.visibility(), 0.75f);
    EXPECT_EQ(f.boxes(1).object_id(), 101u);
    EXPECT_EQ(f.boxes(1).object_class(), proto::OBJECT_CLASS_BUILDING);
    EXPECT_EQ(f.boxes(1).width(), kWidth);
    ExpectGroundTruth3d(f);
  }

  static void ExpectVec3(const proto::Vec3& sent, const Eigen::Vector3d& v) {
    EXPECT_EQ(Eigen::Vector3d(sent.x(), sent.y(), sent.z()), v);
  }

  static void ExpectQuaternion(const proto::Quaternion& sent, const Eigen::Quaterniond& q) {
    EXPECT_EQ(Eigen::Vector4d(sent.x(), sent.y(), sent.z(), sent.w()), q.coeffs());
  }

  // The camera model and the objects, exactly as in the frame.
  void ExpectGroundTruth3d(const proto::Frame& f) const {
    const render::CameraIntrinsics& k = frame_->intrinsics;
    ASSERT_TRUE(f.has_camera_intrinsics());
    EXPECT_EQ(f.camera_intrinsics().fx(), k.fx);
    EXPECT_EQ(f.camera_intrinsics().fy(), k.fy);
    EXPECT_EQ(f.camera_intrinsics().cx(), k.cx);
    EXPECT_EQ(f.camera_intrinsics().cy(), k.cy);
    EXPECT_EQ(f.camera_intrinsics().width(), k.width);
    EXPECT_EQ(f.camera_intrinsics().height(), k.height);
    ASSERT_TRUE(f.has_camera_pose());
    ExpectVec3(f.camera_pose().position(), frame_->camera_pose.position);
    ExpectQuaternion(f.camera_pose().orientation(), frame_->camera_pose.orientation);
    ASSERT_EQ(f.objects_size(), 2);
    for (int i = 0; i < f.objects_size(); ++i) {
      const proto::ObjectGroundTruth& sent = f.objects(i);
      const render::ObjectGroundTruth& object = frame_->objects[i];
      EXPECT_EQ(sent.object_id(), object.instance);
      EXPECT_EQ(sent.object_class(), static_cast<proto::ObjectClass>(object.object_class));
      ExpectVec3(sent.position(), object.position);
      ExpectQuaternion(sent.orientation(), object.orientation);
      ExpectVec3(sent.linear_velocity(), object.linear_velocity);
      ExpectVec3(sent.angular_velocity(), object.angular_velocity);
      ExpectVec3(sent.half_extents(), object.half_extents);
      EXPECT_EQ(sent.projected_box().x(), object.projected_box.x);
      EXPECT_EQ(sent.projected_box().y(), object.projected_box.y);
      EXPECT_EQ(sent.projected_box().width(), object.projected_box.width);
      EXPECT_EQ(sent.projected_box().height(), object.projected_box.height);
      EXPECT_EQ(sent.has_visible_box(), object.has_visible_box);
    }
    EXPECT_FALSE(f.objects(1).has_visible_box());
    EXPECT_TRUE(f.objects(1).has_linear_velocity()) << "zero velocities are sent, not left out";
  }

  static void ExpectNoGroundTruth(const proto::Frame& f) {
    EXPECT_EQ(f.boxes_size(), 0);
    EXPECT_EQ(f.objects_size(), 0);
    EXPECT_FALSE(f.has_camera_intrinsics());
    EXPECT_FALSE(f.has_camera_pose());
  }

  void ExpectState(const proto::Frame& f) const {
    ASSERT_TRUE(f.has_state());
    EXPECT_EQ(f.state().SerializeAsString(), frame_->state.SerializeAsString());
    EXPECT_EQ(f.state().entities(0).name(), "car");
  }

  // The pixel segments are the frame's own buffers, in subscription order.
  void ExpectZeroCopy(const std::vector<proto::Channel>& pixel_channels) const {
    const auto segments = encoder_.segments();
    ASSERT_EQ(segments.size(), pixel_channels.empty() ? 1u : 2 * pixel_channels.size());
    const std::size_t pixels = static_cast<std::size_t>(frame_->width) * frame_->height;
    for (std::size_t i = 0; i < pixel_channels.size(); ++i) {
      const Segment& s = segments[2 * i + 1];
      switch (pixel_channels[i]) {
        case proto::CHANNEL_RGB:
          EXPECT_EQ(s.data, frame_->Pixels(proto::CHANNEL_RGB));
          EXPECT_EQ(s.size, pixels * 3);
          break;
        case proto::CHANNEL_DEPTH:
          EXPECT_EQ(s.data, frame_->Pixels(proto::CHANNEL_DEPTH));
          EXPECT_EQ(s.size, pixels * 4);
          break;
        case proto::CHANNEL_MASK:
          EXPECT_EQ(s.data, frame_->Pixels(proto::CHANNEL_MASK));
          EXPECT_EQ(s.size, pixels * 2);
          break;
        default: ADD_FAILURE();
      }
    }
  }

  session::FramePool pool_;
  session::Frame* writable_ = nullptr;
  session::FrameRef frame_;
  FrameEncoder encoder_;
};

TEST_F(FrameEncodingTest, RgbOnly) {
  for (bool prefix : {false, true}) {
    SCOPED_TRACE(prefix ? "with prefix" : "without prefix");
    const proto::Envelope envelope = EncodeAndParse({proto::CHANNEL_RGB}, false, 0, prefix);
    const proto::Frame& f = envelope.frame();
    ExpectMeta(f, 0);
    ASSERT_EQ(f.images_size(), 1);
    ExpectImage(f.images(0), proto::CHANNEL_RGB);
    ExpectNoGroundTruth(f);
    EXPECT_FALSE(f.has_state());
    ExpectZeroCopy({proto::CHANNEL_RGB});
  }
}

TEST_F(FrameEncodingTest, AllChannelsInSubscriptionOrder) {
  const std::vector<proto::Channel> order = {proto::CHANNEL_MASK, proto::CHANNEL_DEPTH, proto::CHANNEL_RGB,
                                             proto::CHANNEL_BOXES};
  for (bool prefix : {false, true}) {
    SCOPED_TRACE(prefix ? "with prefix" : "without prefix");
    const proto::Envelope envelope = EncodeAndParse(order, true, 17, prefix);
    const proto::Frame& f = envelope.frame();
    ExpectMeta(f, 17);
    ASSERT_EQ(f.images_size(), 3);
    ExpectImage(f.images(0), proto::CHANNEL_MASK);
    ExpectImage(f.images(1), proto::CHANNEL_DEPTH);
    ExpectImage(f.images(2), proto::CHANNEL_RGB);
    ExpectBoxes(f);
    ExpectState(f);
    ExpectZeroCopy({proto::CHANNEL_MASK, proto::CHANNEL_DEPTH, proto::CHANNEL_RGB});
  }
}

TEST_F(FrameEncodingTest, BoxesOnlyHasNoImages) {
  for (bool prefix : {false, true}) {
    SCOPED_TRACE(prefix ? "with prefix" : "without prefix");
    const proto::Envelope envelope = EncodeAndParse({proto::CHANNEL_BOXES}, false, 3, prefix);
    const proto::Frame& f = envelope.frame();
    ExpectMeta(f, 3);
    EXPECT_EQ(f.images_size(), 0);
    ExpectBoxes(f);
    EXPECT_FALSE(f.has_state());
    ExpectZeroCopy({});
  }
}

TEST_F(FrameEncodingTest, BoxesBetweenPixelChannelsAndStateOnlyWhenAsked) {
  const proto::Envelope envelope =
      EncodeAndParse({proto::CHANNEL_DEPTH, proto::CHANNEL_BOXES, proto::CHANNEL_RGB}, false, 0, true);
  const proto::Frame& f = envelope.frame();
  ASSERT_EQ(f.images_size(), 2);
  ExpectImage(f.images(0), proto::CHANNEL_DEPTH);
  ExpectImage(f.images(1), proto::CHANNEL_RGB);
  ExpectBoxes(f);
  EXPECT_FALSE(f.has_state());
  ExpectZeroCopy({proto::CHANNEL_DEPTH, proto::CHANNEL_RGB});
}

TEST_F(FrameEncodingTest, CameraAndObjectsTravelOnlyWithBoxes) {
  const proto::Envelope without =
      EncodeAndParse({proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK}, true, 0, true);
  ExpectNoGroundTruth(without.frame());
  const proto::Envelope with = EncodeAndParse({proto::CHANNEL_BOXES}, false, 0, true);
  ExpectBoxes(with.frame());
}

TEST_F(FrameEncodingTest, WarmEncoderAllocatesNothing) {
  const proto::Subscribed everything =
      Subscription({proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK, proto::CHANNEL_BOXES});
  writable_->objects.resize(200, writable_->objects.front());  // as many as a dense map shows
  for (int warm_up = 0; warm_up < 3; ++warm_up) encoder_.Encode(*frame_, "uav", everything, true, 0, true);
  EXPECT_EQ(testing::AllocationsIn([&] {
              for (int frame = 0; frame < 10; ++frame) encoder_.Encode(*frame_, "uav", everything, true, 0, true);
            }),
            0u);
  EXPECT_EQ(Concatenate().size(), encoder_.total_size());
}

TEST_F(FrameEncodingTest, EncoderReuseCarriesNothingOver) {
  EncodeAndParse({proto::CHANNEL_MASK, proto::CHANNEL_DEPTH, proto::CHANNEL_RGB, proto::CHANNEL_BOXES}, true, 9, true);
  const proto::Envelope envelope = EncodeAndParse({proto::CHANNEL_RGB}, false, 0, false);
  const proto::Frame& f = envelope.frame();
  ExpectMeta(f, 0);
  ASSERT_EQ(f.images_size(), 1);
  ExpectImage(f.images(0), proto::CHANNEL_RGB);
  ExpectNoGroundTruth(f);
  EXPECT_FALSE(f.has_state());
  ExpectZeroCopy({proto::CHANNEL_RGB});
}

TEST_F(FrameEncodingTest, EmptyStateIsStillPresentWhenAsked) {
  writable_->state.Clear();
  const proto::Envelope envelope = EncodeAndParse({proto::CHANNEL_RGB}, true, 0, false);
  EXPECT_TRUE(envelope.frame().has_state());
}

TEST_F(FrameEncodingTest, FullSizeFrameWithMultiByteLengths) {
  // 320x180: the pixel fields' lengths need three-byte varints.
  session::Frame* big = nullptr;
  session::FrameRef ref = pool_.Acquire(&big);
  FillFrame(*big, 320, 180);
  frame_ = ref;
  const proto::Envelope envelope =
      EncodeAndParse({proto::CHANNEL_DEPTH, proto::CHANNEL_RGB, proto::CHANNEL_MASK}, true, 1u << 20, true);
  const proto::Frame& f = envelope.frame();
  ExpectMeta(f, 1u << 20);
  ASSERT_EQ(f.images_size(), 3);
  ExpectImage(f.images(0), proto::CHANNEL_DEPTH);
  ExpectImage(f.images(1), proto::CHANNEL_RGB);
  ExpectImage(f.images(2), proto::CHANNEL_MASK);
  ExpectNoGroundTruth(f);
  ExpectState(f);
  ExpectZeroCopy({proto::CHANNEL_DEPTH, proto::CHANNEL_RGB, proto::CHANNEL_MASK});
}

TEST_F(FrameEncodingTest, SegmentsCoverTheTotalSize) {
  encoder_.Encode(*frame_, "uav", Subscription({proto::CHANNEL_RGB, proto::CHANNEL_MASK}), true, 0, true);
  std::size_t sum = 0;
  for (const Segment& s : encoder_.segments()) {
    EXPECT_NE(s.data, nullptr);
    EXPECT_GT(s.size, 0u);
    sum += s.size;
  }
  EXPECT_EQ(sum, encoder_.total_size());
}

}  // namespace
}  // namespace sim4cv::transport
