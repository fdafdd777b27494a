#include "server/render/ground_truth.h"

#include <gtest/gtest.h>

#include <vector>

namespace sim4cv::render {
namespace {

// A blank mask to paint rectangles of instance ids into.
struct Mask {
  uint32_t width, height;
  std::vector<uint16_t> pixels;
  Mask(uint32_t w, uint32_t h) : width(w), height(h), pixels(size_t{w} * h, kUnlabelled) {}
  void Fill(uint32_t x, uint32_t y, uint32_t w, uint32_t h, InstanceId id) {
    for (uint32_t row = y; row < y + h; ++row) {
      for (uint32_t column = x; column < x + w; ++column) pixels[size_t{row} * width + column] = id;
    }
  }
};

std::vector<GroundTruthBox> Extract(BoxExtractor& extractor, const Mask& mask,
                                    const std::vector<LabelledObject>& objects) {
  std::vector<GroundTruthBox> boxes;
  extractor.Extract(mask.pixels.data(), mask.width, mask.height, objects, boxes);
  return boxes;
}

void ExpectBox(const GroundTruthBox& box, InstanceId id, uint32_t x, uint32_t y, uint32_t w, uint32_t h) {
  EXPECT_EQ(box.instance, id);
  EXPECT_EQ(box.x, x);
  EXPECT_EQ(box.y, y);
  EXPECT_EQ(box.width, w);
  EXPECT_EQ(box.height, h);
}

TEST(BoxExtractor, OneObjectGetsItsTightBox) {
  Mask mask(20, 10);
  mask.Fill(3, 2, 5, 4, 7);
  BoxExtractor extractor;
  const auto boxes = Extract(extractor, mask, {{7, 3, 20}});
  ASSERT_EQ(boxes.size(), 1u);
  ExpectBox(boxes[0], 7, 3, 2, 5, 4);
  EXPECT_EQ(boxes[0].object_class, 3u);
  EXPECT_EQ(boxes[0].visible_pixels, 20u);
  EXPECT_FLOAT_EQ(boxes[0].visibility, 1.0f);
}

TEST(BoxExtractor, TwoObjectsComeOutOrderedById) {
  Mask mask(20, 10);
  mask.Fill(10, 0, 2, 2, 9);
  mask.Fill(0, 5, 3, 1, 4);
  BoxExtractor extractor;
  const auto boxes = Extract(extractor, mask, {{9, 1, 4}, {4, 2, 3}});
  ASSERT_EQ(boxes.size(), 2u);
  ExpectBox(boxes[0], 4, 0, 5, 3, 1);
  EXPECT_EQ(boxes[0].object_class, 2u);
  ExpectBox(boxes[1], 9, 10, 0, 2, 2);
  EXPECT_EQ(boxes[1].object_class, 1u);
}

TEST(BoxExtractor, ObjectTouchingTheBorderReachesTheLastColumnAndRow) {
  Mask mask(16, 8);
  mask.Fill(12, 5, 4, 3, 1);
  mask.Fill(0, 0, 1, 1, 2);
  BoxExtractor extractor;
  const auto boxes = Extract(extractor, mask, {{1, 0, 12}, {2, 0, 1}});
  ASSERT_EQ(boxes.size(), 2u);
  ExpectBox(boxes[0], 1, 12, 5, 4, 3);
  EXPECT_EQ(boxes[0].x + boxes[0].width, mask.width);
  EXPECT_EQ(boxes[0].y + boxes[0].height, mask.height);
  ExpectBox(boxes[1], 2, 0, 0, 1, 1);
}

TEST(BoxExtractor, IdsNotListedAreIgnored) {
  Mask mask(10, 10);
  mask.Fill(0, 0, 2, 2, 3);
  mask.Fill(5, 5, 2, 2, 8);  // above the largest listed id
  mask.Fill(8, 0, 1, 1, 1);  // below it
  BoxExtractor extractor;
  const auto boxes = Extract(extractor, mask, {{3, 0, 4}});
  ASSERT_EQ(boxes.size(), 1u);
  ExpectBox(boxes[0], 3, 0, 0, 2, 2);
}

TEST(BoxExtractor, ObjectWithoutVisiblePixelsIsOmitted) {
  Mask mask(10, 10);
  mask.Fill(1, 1, 2, 2, 5);
  BoxExtractor extractor;
  const auto boxes = Extract(extractor, mask, {{5, 0, 4}, {6, 0, 30}});
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_EQ(boxes[0].instance, 5);
}

TEST(BoxExtractor, VisibilityIsVisibleOverUnoccludedClampedToOne) {
  Mask mask(10, 10);
  mask.Fill(0, 0, 4, 5, 1);  // 20 visible of 80
  mask.Fill(5, 0, 2, 2, 2);  // 4 visible, unoccluded count too small (clamped)
  mask.Fill(8, 8, 1, 1, 3);  // 1 visible, unoccluded unknown
  BoxExtractor extractor;
  const auto boxes = Extract(extractor, mask, {{1, 0, 80}, {2, 0, 3}, {3, 0, 0}});
  ASSERT_EQ(boxes.size(), 3u);
  EXPECT_EQ(boxes[0].visible_pixels, 20u);
  EXPECT_FLOAT_EQ(boxes[0].visibility, 0.25f);
  EXPECT_FLOAT_EQ(boxes[1].visibility, 1.0f);
  EXPECT_FLOAT_EQ(boxes[2].visibility, 1.0f);
}

TEST(BoxExtractor, ReuseDoesNotCarryResultsOver) {
  BoxExtractor extractor;
  Mask first(10, 10);
  first.Fill(0, 0, 10, 10, 2);
  first.Fill(0, 0, 1, 1, 1);
  Extract(extractor, first, {{1, 0, 1}, {2, 0, 99}});

  Mask second(10, 10);
  second.Fill(4, 4, 2, 3, 2);
  // Id 1 is absent from this mask; id 3 was never seen before.
  const auto boxes = Extract(extractor, second, {{1, 0, 1}, {2, 0, 6}, {3, 0, 5}});
  ASSERT_EQ(boxes.size(), 1u);
  ExpectBox(boxes[0], 2, 4, 4, 2, 3);
  EXPECT_EQ(boxes[0].visible_pixels, 6u);
  EXPECT_FLOAT_EQ(boxes[0].visibility, 1.0f);
}

TEST(BoxExtractor, NoObjectsGiveNoBoxes) {
  Mask mask(4, 4);
  mask.Fill(0, 0, 4, 4, 1);
  BoxExtractor extractor;
  std::vector<GroundTruthBox> boxes(3);
  extractor.Extract(mask.pixels.data(), mask.width, mask.height, {}, boxes);
  EXPECT_TRUE(boxes.empty());
}

}  // namespace
}  // namespace sim4cv::render
