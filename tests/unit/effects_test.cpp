// The camera effects (protocol/effects.h) on the real OSMesa renderer:
// effects that change RGB leave every ground-truth channel byte-identical;
// a lens distorts every channel by OpenCV's model (checked against
// cv::projectPoints), keeps ids and depths exact values, and keeps each
// object's visibility; every effect repeats byte for byte.
#include "protocol/effects.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <random>
#include <string>
#include <vector>

#include "server/render/gl_context.h"
#include "server/render/ground_truth.h"
#include "server/render/lens.h"
#include "server/render/projection.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/wire/effects_wire.h"
#include "server/sim/world.h"
#include "tests/support/no_warnings.h"
#include "tests/support/rendered_frame.h"
#include "tests/unit/urban_render_support.h"

namespace sim4cv::render {
namespace {

effects::CameraEffects Lens() { return effects::WideAngleLens(); }

TEST(EffectsTableTest, EveryEffectIsOffByDefaultAndHasItsProtoField) {
  EXPECT_FALSE(effects::Any(effects::CameraEffects{}));
  EXPECT_EQ(effects::Describe(effects::CameraEffects{}), "none");
  effects::CameraEffects all;
  double value = 0.25;
  for (const effects::EffectInfo& info : effects::kEffects) {
    EXPECT_GE(info.off, info.min) << info.field;
    EXPECT_LE(info.off, info.max) << info.field;
    all.*info.member = std::clamp(std::round(info.min + value * (info.max - info.min)), info.min, info.max);
    if (info.field != "antialias" && info.field != "jpeg_quality")
      all.*info.member = info.min + value * (info.max - info.min);
    value = std::fmod(value + 0.1, 0.5);
  }
  proto::CameraEffects message;
  wire::FillEffects(all, message);  // DEMANDs a proto field per entry
  effects::CameraEffects back;
  wire::ApplyEffects(message, back);
  EXPECT_EQ(back, all);
  proto::CameraEffects only_blur;
  only_blur.set_motion_blur(0.5);
  wire::ApplyEffects(only_blur, back);
  EXPECT_EQ(back.motion_blur, 0.5);
  EXPECT_EQ(back.k1, all.k1) << "fields left out keep their value";
}

TEST(EffectsTableTest, BadValuesAreNamedWithTheirRange) {
  effects::CameraEffects e;
  e.motion_blur = 1.5;
  EXPECT_EQ(effects::Check(e, true), "--motion-blur 1.5 is outside 0..1 frames");
  EXPECT_EQ(effects::Check(e, false), "SetEffects.motion_blur 1.5 is outside 0..1 frames");
  e = {};
  e.jpeg_quality = 50.5;
  EXPECT_EQ(effects::Check(e, false), "SetEffects.jpeg_quality 50.5 is not a whole number");
  e = {};
  e.white_balance_k = 1000;
  EXPECT_EQ(effects::Check(e, true), "--white-balance 1000 is outside 2000..12000 K");
  e = {};
  e.k1 = -0.9;
  EXPECT_EQ(effects::Check(e, true).rfind("the lens k1=-0.9 k2=0 k3=0 folds the image at radius 0.40", 0), 0u)
      << effects::Check(e, true);
  EXPECT_EQ(effects::Check(Lens(), true), "");
  EXPECT_EQ(effects::CheckRanges(e, false), "") << "a folding coefficient is in range; only a whole lens folds";
  e.k2 = 0.5;  // balances k1: 1 - 2.7 r^2 + 2.5 r^4 never reaches 0
  EXPECT_EQ(effects::CheckLens(e), "");
  e = {};
  e.k1 = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(effects::Check(e, false), "SetEffects.k1 nan is outside -1..1");
}

TEST(EffectsTableTest, UndistortInvertsOpenCvsModel) {
  const effects::CameraEffects lens = Lens();
  const cv::Mat camera = cv::Mat::eye(3, 3, CV_64F);
  const cv::Mat coefficients = (cv::Mat_<double>(1, 5) << lens.k1, lens.k2, lens.p1, lens.p2, lens.k3);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-1.2, 1.2);
  for (int i = 0; i < 200; ++i) {
    const double x = coordinate(random), y = coordinate(random) * 0.6;
    std::vector<cv::Point2d> projected;
    cv::projectPoints(std::vector<cv::Point3d>{{x, y, 1.0}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera,
                      coefficients, projected);
    double xd = 0, yd = 0;
    effects::Distort(lens, x, y, xd, yd);
    EXPECT_NEAR(xd, projected[0].x, 1e-12);
    EXPECT_NEAR(yd, projected[0].y, 1e-12);
    double ux = 0, uy = 0;
    ASSERT_TRUE(effects::Undistort(lens, xd, yd, ux, uy));
    EXPECT_NEAR(ux, x, 1e-9);
    EXPECT_NEAR(uy, y, 1e-9);
  }
}

TEST(EffectsTableTest, TheLensMapSendsEachPixelToWhereTheModelSaysItCameFrom) {
  CameraView view;
  view.width = 160;
  view.height = 90;
  view.fov_y_deg = 60.0f;
  view.effects = Lens();
  const LensMap map = MakeLensMap(view);
  EXPECT_GT(map.widening, 1.05f) << "a barrel lens sees more than the pinhole";
  for (uint32_t row = 0; row < view.height; row += 7) {
    for (uint32_t column = 0; column < view.width; column += 5) {
      const std::size_t i = 2 * (std::size_t{row} * view.width + column);
      EXPECT_GE(map.source[i], 0.5f);
      EXPECT_LE(map.source[i], view.width - 0.5f);
      EXPECT_GE(map.source[i + 1], 0.5f);
      EXPECT_LE(map.source[i + 1], view.height - 0.5f);
      double u = 0, v = 0;
      DistortPixel(view, map.widening, map.source[i], map.source[i + 1], u, v);
      EXPECT_NEAR(u, column + 0.5, 1e-3);
      EXPECT_NEAR(v, row + 0.5, 1e-3);
    }
  }
}

// The 3D box's image through a lens follows the curved edges: compare with
// OpenCV projecting thousands of points of the box's surface.
TEST(EffectsTableTest, ProjectedBoxesFollowOpenCvsDistortion) {
  CameraView view;
  view.width = 320;
  view.height = 180;
  view.fov_y_deg = 60.0f;
  view.effects = Lens();
  const BoxProjector projector(view);
  const CameraIntrinsics k = projector.intrinsics();
  const cv::Mat camera = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const cv::Mat coefficients = (cv::Mat_<double>(1, 5) << k.lens.k1, k.lens.k2, k.lens.p1, k.lens.p2, k.lens.k3);
  const Pose pose = OpenCvPoseOf(view);
  // Boxes in front of the camera (OpenGL camera at the origin looks along -z).
  for (const Eigen::Vector3d& centre :
       {Eigen::Vector3d(-3.0, 1.0, -9.0), Eigen::Vector3d(2.5, -1.2, -7.0), Eigen::Vector3d(0.2, 0.1, -20.0)}) {
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1.0, 0.2).normalized()));
    const Eigen::Vector3d half(1.8, 0.8, 0.9);
    const ImageRect rect = projector.Project(centre, turn, half);
    std::vector<cv::Point3d> surface;
    for (int face = 0; face < 3; ++face) {
      for (double sign : {-1.0, 1.0}) {
        for (int a = 0; a <= 40; ++a) {
          for (int b = 0; b <= 40; ++b) {
            Eigen::Vector3d local;
            local[face] = sign;
            local[(face + 1) % 3] = -1.0 + a / 20.0;
            local[(face + 2) % 3] = -1.0 + b / 20.0;
            const Eigen::Vector3d world = centre + turn * local.cwiseProduct(half);
            const Eigen::Vector3d in_camera = pose.orientation.inverse() * (world - pose.position);
            surface.emplace_back(in_camera.x(), in_camera.y(), in_camera.z());
          }
        }
      }
    }
    std::vector<cv::Point2d> pixels;
    cv::projectPoints(surface, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), camera, coefficients, pixels);
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (const cv::Point2d& p : pixels) {
      x0 = std::min(x0, p.x);
      y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
    }
    x0 = std::max(x0, 0.0);
    y0 = std::max(y0, 0.0);
    x1 = std::min(x1, 320.0);
    y1 = std::min(y1, 180.0);
    ASSERT_FALSE(rect.empty());
    EXPECT_NEAR(rect.x, x0, 0.05);
    EXPECT_NEAR(rect.y, y0, 0.05);
    EXPECT_NEAR(rect.x + rect.width, x1, 0.05);
    EXPECT_NEAR(rect.y + rect.height, y1, 0.05);
  }
}

// Every camera of the urban map (urban_render_support.h), with effects,
// and a second renderer for the finer pinhole renders a lens is checked on.
class EffectsRenderTest : public testing::UrbanRenderTest {
 protected:
  static void SetUpTestSuite() {
    UrbanRenderTest::SetUpTestSuite();
    fine_renderer_ = std::make_unique<Renderer>(graphics_->meshes(), 4 * kWidth, 4 * kHeight);
  }
  static void TearDownTestSuite() {
    fine_renderer_.reset();
    UrbanRenderTest::TearDownTestSuite();
  }

  static CameraView View(std::size_t index, const effects::CameraEffects& effects) {
    CameraView view = UrbanRenderTest::View(index);
    view.effects = effects;
    return view;
  }
  using UrbanRenderTest::Render;
  static Shot Render(std::size_t index, const effects::CameraEffects& effects) { return Render(View(index, effects)); }

  // What a lens looks into: the pinhole view widened by the lens map, at
  // `scale` times the camera's resolution (the renderer draws ground truth at 2).
  static CameraView Pinhole(const CameraView& lensed, const LensMap& map, uint32_t scale) {
    CameraView pinhole = lensed;
    pinhole.effects = {};
    pinhole.fov_y_deg = WidenedFov(lensed.fov_y_deg, map.widening);
    pinhole.width *= scale;
    pinhole.height *= scale;
    return pinhole;
  }
  static sim4cv::testing::RenderedFrame RenderFine(const CameraView& pinhole) {
    sim4cv::testing::RenderedFrame frame(pinhole.width, pinhole.height);
    fine_renderer_->Render(pinhole, graphics_->draw_items(), frame.Buffers(channels::kAllPixels), {});
    return frame;
  }

  inline static std::unique_ptr<Renderer> fine_renderer_;
};

using testing::SameBytes;

double Psnr(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
  return 10.0 * std::log10(255.0 * 255.0 / (sum / static_cast<double>(a.size())));
}

// Mean of channel c (0 red .. 2 blue) over the image.
double Mean(const std::vector<uint8_t>& rgb, int c) {
  double sum = 0;
  for (std::size_t i = static_cast<std::size_t>(c); i < rgb.size(); i += 3) sum += rgb[i];
  return sum / static_cast<double>(rgb.size() / 3);
}

TEST_F(EffectsRenderTest, RgbEffectsLeaveEveryGroundTruthChannelByteIdenticalAndRepeat) {
  using effects::CameraEffects;
  CameraEffects several = effects::Only(&CameraEffects::jpeg_quality, 30);
  several.antialias = 1;
  several.motion_blur = 0.5;
  several.white_balance_k = 9000;
  const std::vector<std::pair<std::string, CameraEffects>> cases = {
      {"antialias", effects::Only(&CameraEffects::antialias, 1)},
      {"exposure", effects::Only(&CameraEffects::exposure_ev, 1.0)},
      {"white balance", effects::Only(&CameraEffects::white_balance_k, 3200)},
      {"motion blur", effects::Only(&CameraEffects::motion_blur, 1.0)},
      {"jpeg", effects::Only(&CameraEffects::jpeg_quality, 30)},
      {"all but the lens", several}};
  for (std::size_t camera = 0; camera < scene_->cameras.size(); ++camera) {
    SCOPED_TRACE(scene_->cameras[camera].name);
    const Shot plain = Render(camera, {});
    for (const auto& [name, effects] : cases) {
      SCOPED_TRACE(name);
      const Shot shot = Render(camera, effects);
      EXPECT_TRUE(SameBytes(shot.frame.depth, plain.frame.depth));
      EXPECT_TRUE(SameBytes(shot.frame.mask, plain.frame.mask));
      EXPECT_TRUE(SameBytes(shot.frame.semantic, plain.frame.semantic));
      EXPECT_TRUE(SameBytes(shot.frame.normals, plain.frame.normals));
      EXPECT_TRUE(SameBytes(shot.frame.flow, plain.frame.flow));
      EXPECT_EQ(shot.unoccluded, plain.unoccluded);
      EXPECT_FALSE(SameBytes(shot.frame.rgb, plain.frame.rgb)) << "the effect shows";
      EXPECT_TRUE(SameBytes(Render(camera, effects).frame.rgb, shot.frame.rgb)) << "and repeats";
    }
  }
}

TEST_F(EffectsRenderTest, EachRgbEffectDoesWhatItSays) {
  const std::size_t chase = 2;
  const Shot plain = Render(chase, {});
  effects::CameraEffects e;
  e.exposure_ev = 1.0;
  EXPECT_GT(Mean(Render(chase, e).frame.rgb, 1), Mean(plain.frame.rgb, 1) * 1.15) << "+1 EV is brighter";
  e = {};
  e.white_balance_k = 3200;  // balanced for tungsten under daylight: blue
  const Shot tungsten = Render(chase, e);
  EXPECT_GT(Mean(tungsten.frame.rgb, 2) / Mean(tungsten.frame.rgb, 0),
            1.15 * Mean(plain.frame.rgb, 2) / Mean(plain.frame.rgb, 0));
  e = {};
  e.jpeg_quality = 90;
  const double fine = Psnr(Render(chase, e).frame.rgb, plain.frame.rgb);
  e.jpeg_quality = 10;
  const double coarse = Psnr(Render(chase, e).frame.rgb, plain.frame.rgb);
  EXPECT_GT(fine, 30.0);
  EXPECT_LT(coarse, fine - 5.0);
  // Anti-aliasing touches edges, not flat areas: most pixels stay.
  e = {};
  e.antialias = 1;
  const Shot smooth = Render(chase, e);
  std::size_t changed = 0;
  for (std::size_t i = 0; i < plain.frame.rgb.size(); ++i) changed += smooth.frame.rgb[i] != plain.frame.rgb[i];
  EXPECT_GT(changed, plain.frame.rgb.size() / 100);
  EXPECT_LT(changed, plain.frame.rgb.size() / 2);
  // Motion blur smears where the image moves; pixels that do not move (the
  // sky, whose flow is 0 for a camera that only slides) keep their colour.
  e = {};
  e.motion_blur = 1.0;
  const Shot blurred = Render(chase, e);
  std::size_t still = 0, still_same = 0;
  for (std::size_t p = 0; p < plain.frame.depth.size(); ++p) {
    const float fx = plain.frame.flow[2 * p], fy = plain.frame.flow[2 * p + 1];
    if (fx * fx + fy * fy > 1e-6f) continue;
    ++still;
    still_same += std::equal(&blurred.frame.rgb[3 * p], &blurred.frame.rgb[3 * p + 3], &plain.frame.rgb[3 * p]);
  }
  ASSERT_GT(still, 100u);
  EXPECT_EQ(still_same, still);
  EXPECT_LT(Psnr(blurred.frame.rgb, plain.frame.rgb), 40.0) << "moving parts are smeared";
}

// With a lens, every channel is the undistorted (widened) render looked up
// through the lens map: the same ids, depths, labels and normals, moved.
TEST_F(EffectsRenderTest, ALensDistortsEveryChannelAlikeByTheModel) {
  for (std::size_t camera = 0; camera < scene_->cameras.size(); ++camera) {
    SCOPED_TRACE(scene_->cameras[camera].name);
    const CameraView lensed = View(camera, Lens());
    const Shot distorted = Render(lensed);
    // The widened pinhole view the lens map points into.
    const LensMap map = MakeLensMap(lensed);
    const sim4cv::testing::RenderedFrame fine = RenderFine(Pinhole(lensed, map, 2));
    std::size_t agree = 0;
    const std::size_t pixels = std::size_t{kWidth} * kHeight;
    for (std::size_t p = 0; p < pixels; ++p) {
      const auto column = static_cast<uint32_t>(2 * map.source[2 * p]);
      const auto row = static_cast<uint32_t>(2 * map.source[2 * p + 1]);
      const std::size_t s = fine.At(column, row);
      agree += distorted.frame.mask[p] == fine.mask[s] && distorted.frame.semantic[p] == fine.semantic[s] &&
               std::memcmp(&distorted.frame.depth[p], &fine.depth[s], sizeof(float)) == 0 &&
               std::memcmp(&distorted.frame.normals[3 * p], &fine.normals[3 * s], 3 * sizeof(float)) == 0;
    }
    EXPECT_EQ(agree, pixels) << "every pixel holds its source point's exact values";
    const Shot wide = Render(Pinhole(lensed, map, 1));
    // Visibility means the same with and without the lens.
    std::vector<LabelledObject> objects;
    for (InstanceId id = 1; id < distorted.unoccluded.size(); ++id) {
      if (distorted.unoccluded[id] > 0) objects.push_back({id, 1, distorted.unoccluded[id]});
    }
    std::vector<GroundTruthBox> boxes;
    BoxExtractor extractor;
    extractor.Extract(distorted.frame.mask.data(), kWidth, kHeight, objects, boxes);
    ASSERT_FALSE(boxes.empty());
    for (const GroundTruthBox& box : boxes) {
      if (box.visible_pixels < 40) continue;  // a few pixels: the ratio is noise
      const uint32_t wide_visible = wide.frame.Count(box.instance);
      ASSERT_GT(wide.unoccluded[box.instance], 0u);
      EXPECT_NEAR(box.visibility, std::min(1.0, double(wide_visible) / wide.unoccluded[box.instance]), 0.02)
          << "instance " << box.instance;
    }
  }
}

// The boxes of the distorted mask against references made independently
// with OpenCV: every pixel centre of the distorted image taken back through
// cv::undistortPoints and looked up in a pinhole render. At the renderer's
// own ground-truth resolution (twice the image's) every box edge must be
// exactly where OpenCV's model puts it. Against a render twice finer still,
// an edge may move one pixel where the outline passes within a fraction of
// a pixel centre, and sub-pixel-thin parts (a far lantern's pole) that
// point sampling misses at one resolution and hits at the other move more:
// measured and bounded on average.
TEST_F(EffectsRenderTest, DistortedBoxesMatchOpenCvsModelWithinHalfAPixel) {
  for (const uint32_t scale : {2u, 4u}) {
    int edges = 0, moved = 0;
    double worst = 0;
    for (std::size_t view = 0; view < scene_->cameras.size(); ++view) {
      const CameraView lensed = View(view, Lens());
      const Shot distorted = Render(lensed);
      const LensMap map = MakeLensMap(lensed);
      const CameraView pinhole = Pinhole(lensed, map, scale);
      const sim4cv::testing::RenderedFrame fine = RenderFine(pinhole);
      const CameraIntrinsics k = IntrinsicsOf(lensed), kf = IntrinsicsOf(pinhole);
      const cv::Mat camera = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
      const cv::Mat coefficients = (cv::Mat_<double>(1, 5) << k.lens.k1, k.lens.k2, k.lens.p1, k.lens.p2, k.lens.k3);
      std::vector<cv::Point2d> centres, rays;
      for (uint32_t row = 0; row < kHeight; ++row) {
        for (uint32_t column = 0; column < kWidth; ++column) centres.emplace_back(column + 0.5, row + 0.5);
      }
      cv::undistortPoints(centres, rays, camera, coefficients, cv::noArray(), cv::noArray(),
                          cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
      std::vector<uint16_t> reference(centres.size());
      for (std::size_t p = 0; p < rays.size(); ++p) {
        const double u = rays[p].x * kf.fx + kf.cx, v = rays[p].y * kf.fy + kf.cy;
        ASSERT_TRUE(u >= 0 && v >= 0 && u < pinhole.width && v < pinhole.height) << "the widened view covers the lens";
        reference[p] = fine.mask[fine.At(static_cast<uint32_t>(u), static_cast<uint32_t>(v))];
      }
      std::vector<LabelledObject> objects;
      for (InstanceId id = 1; id < distorted.unoccluded.size(); ++id) objects.push_back({id, 1, 1});
      std::vector<GroundTruthBox> boxes, expected;
      BoxExtractor extractor;
      extractor.Extract(distorted.frame.mask.data(), kWidth, kHeight, objects, boxes);
      extractor.Extract(reference.data(), kWidth, kHeight, objects, expected);
      for (const GroundTruthBox& box : boxes) {
        const auto match = std::find_if(expected.begin(), expected.end(),
                                        [&](const GroundTruthBox& e) { return e.instance == box.instance; });
        if (box.visible_pixels < 20 || match == expected.end()) continue;  // specks: nothing to measure
        SCOPED_TRACE(scene_->cameras[view].name + ", instance " + std::to_string(box.instance));
        for (const auto& [ours, theirs] : {std::pair{box.x, match->x}, std::pair{box.y, match->y},
                                           std::pair{box.x + box.width, match->x + match->width},
                                           std::pair{box.y + box.height, match->y + match->height}}) {
          const double off = std::abs(static_cast<double>(ours) - theirs);
          if (scale == 2) {
            EXPECT_EQ(off, 0.0);
          }
          worst = std::max(worst, off);
          moved += static_cast<int>(off);
          ++edges;
        }
      }
    }
    ASSERT_GE(edges, 40) << "enough objects in view";
    const double mean = static_cast<double>(moved) / edges;  // most offsets are 0 or 1 pixel
    EXPECT_LE(mean, 0.5);
    std::printf("reference at %ux: %d box edges, %d moved (mean %.3f px), worst %.0f px\n", scale, edges, moved, mean,
                worst);
  }
}

// A lens whose fold lies inside a wide camera's view: past the fold the
// image is black and holds nothing, and rendering goes on.
TEST_F(EffectsRenderTest, PixelsPastALensesFoldAreEmpty) {
  effects::CameraEffects lens;
  lens.k1 = -0.5;  // folds at 0.54 (tan of the angle): inside a 40-degree view's corners
  ASSERT_EQ(effects::Check(lens, true), "");
  CameraView view = View(1, lens);
  view.fov_y_deg = 40.0f;
  const LensMap map = MakeLensMap(view);
  const Shot shot = Render(view);
  std::size_t past = 0;
  for (std::size_t p = 0; p < shot.frame.depth.size(); ++p) {
    if (map.source[2 * p] >= 0) continue;
    ++past;
    EXPECT_EQ(shot.frame.mask[p], 0);
    EXPECT_TRUE(std::isinf(shot.frame.depth[p]));
    EXPECT_EQ(shot.frame.rgb[3 * p], 0);
  }
  EXPECT_GT(past, 100u) << "the corners lie past the fold";
  EXPECT_LT(past, shot.frame.depth.size() / 2);
}

TEST_F(EffectsRenderTest, FlowThroughALensIsInDistortedPixels) {
  const CameraView lensed = View(0, Lens());
  const Shot distorted = Render(lensed);
  const LensMap map = MakeLensMap(lensed);
  // A pixel's flow points back to where its surface point was a frame ago:
  // the previous frame's render through the same lens shows that point there.
  // Checked on the model: previous = Distort(source - undistorted flow).
  const sim4cv::testing::RenderedFrame fine = RenderFine(Pinhole(lensed, map, 2));
  int checked = 0;
  for (uint32_t row = 5; row < kHeight; row += 11) {
    for (uint32_t column = 5; column < kWidth; column += 13) {
      const std::size_t p = std::size_t{row} * kWidth + column;
      const double qx = map.source[2 * p], qy = map.source[2 * p + 1];
      const std::size_t s = fine.At(static_cast<uint32_t>(2 * qx), static_cast<uint32_t>(2 * qy));
      const float fx = fine.flow[2 * s] / 2, fy = fine.flow[2 * s + 1] / 2;  // in fine pixels
      if (std::isnan(fx)) continue;
      double u = 0, v = 0;
      DistortPixel(lensed, map.widening, qx - fx, qy - fy, u, v);
      EXPECT_NEAR(distorted.frame.flow[2 * p], column + 0.5 - u, 1e-3);
      EXPECT_NEAR(distorted.frame.flow[2 * p + 1], row + 0.5 - v, 1e-3);
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

}  // namespace
}  // namespace sim4cv::render
