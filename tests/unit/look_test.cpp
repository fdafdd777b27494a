// The conditions presets and the look they give (protocol/conditions.h,
// server/render/look.h), and what the full look may and may not change on
// the real OSMesa renderer: RGB only, deterministically; depth, masks,
// visibility counts, semantic labels, normals and flow stay byte-identical
// in every preset and quality.
#include "server/render/look.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "protocol/conditions.h"
#include "server/render/gl_context.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/sim/world.h"
#include "tests/support/no_warnings.h"
#include "tests/support/rendered_frame.h"
#include "tests/unit/urban_render_support.h"

namespace sim4cv::render {
namespace {

using conditions::Preset;
using conditions::Quality;

TEST(ConditionsTest, PresetsAreListedOnceAndFoundByName) {
  std::set<std::string> names;
  for (const conditions::PresetInfo& info : conditions::kPresets) {
    EXPECT_TRUE(names.insert(std::string(info.name)).second) << info.name;
    EXPECT_EQ(conditions::FindByName(info.name), info.preset);
    EXPECT_GE(info.hour, conditions::kMinHour);
    EXPECT_LE(info.hour, conditions::kMaxHour);
    EXPECT_NE(conditions::Names().find(info.name), std::string::npos);
  }
  EXPECT_GE(names.size(), 7u) << "clear noon, clear morning, overcast, fog, dusk, night, rain";
  EXPECT_FALSE(conditions::FindByName("Clear_Noon").has_value());
  EXPECT_EQ(conditions::Describe(conditions::Conditions{Preset::RAIN, 15.0, Quality::kFast}),
            "rain at 15.00 h, fast quality");
}

TEST(ConditionsTest, RandomisationIsReproducibleFromItsSeedAndCoversThePresets) {
  std::set<Preset> seen;
  for (uint64_t draw = 0; draw < 60; ++draw) {
    const conditions::Conditions a = conditions::Randomized(42, draw, conditions::Conditions{});
    const conditions::Conditions b = conditions::Randomized(42, draw, conditions::Conditions{});
    EXPECT_EQ(a.preset, b.preset);
    EXPECT_EQ(a.hour, b.hour);
    EXPECT_EQ(a.exposure, b.exposure);
    EXPECT_EQ(a.variation, b.variation);
    EXPECT_GE(a.hour, conditions::kMinHour);
    EXPECT_LT(a.hour, conditions::kMaxHour);
    EXPECT_GE(a.exposure, 0.7);
    EXPECT_LE(a.exposure, 1.4);
    EXPECT_NE(a.variation, 0u);
    const bool sun_up = LookOf(a).to_sun.z() > 0.0f && LookOf(a).lights < 1.0f;
    EXPECT_EQ(sun_up, a.preset != Preset::NIGHT) << conditions::Describe(a);
    seen.insert(a.preset);
  }
  EXPECT_EQ(seen.size(), conditions::kPresets.size()) << "60 draws reach every preset";
  EXPECT_NE(conditions::Randomized(42, 0, conditions::Conditions{}).variation,
            conditions::Randomized(43, 0, conditions::Conditions{}).variation);
  EXPECT_EQ(conditions::Randomized(42, 0, conditions::Of(Preset::FOG, Quality::kFast)).quality, Quality::kFast);
}

TEST(LookTest, TheSunRisesInTheEastStandsSouthAtNoonAndSetsInTheWest) {
  const auto sun = [](double hour) { return LookOf({Preset::CLEAR_NOON, hour, Quality::kFull}).to_sun; };
  EXPECT_GT(sun(7.0).x(), 0.8f);
  EXPECT_GT(sun(7.0).z(), 0.0f);
  EXPECT_NEAR(sun(12.0).x(), 0.0f, 1e-5f);
  EXPECT_LT(sun(12.0).y(), 0.0f);
  EXPECT_NEAR(sun(12.0).z(), std::sin(65.0f * 3.14159265f / 180.0f), 1e-4f);
  EXPECT_LT(sun(17.0).x(), -0.8f);
  EXPECT_LT(sun(8.0).z(), sun(11.0).z()) << "lower in the morning: longer shadows";
  const Look night = LookOf({Preset::CLEAR_NOON, 23.0, Quality::kFull});
  EXPECT_GT(night.to_sun.z(), 0.0f) << "the moon lights the night";
  EXPECT_FALSE(night.shadows);
  EXPECT_EQ(night.lights, 1.0f);
}

TEST(LookTest, EachPresetLooksAsItsNameSays) {
  const auto look = [](Preset preset) { return LookOf(conditions::Of(preset)); };
  EXPECT_TRUE(look(Preset::CLEAR_NOON).shadows);
  EXPECT_TRUE(look(Preset::CLEAR_MORNING).shadows);
  EXPECT_FALSE(look(Preset::OVERCAST).shadows);
  EXPECT_FALSE(look(Preset::FOG).shadows);
  EXPECT_GT(look(Preset::FOG).fog_density, 5 * look(Preset::RAIN).fog_density) << "fog: about 100 m visibility";
  EXPECT_GT(look(Preset::RAIN).fog_density, look(Preset::CLEAR_NOON).fog_density);
  EXPECT_EQ(look(Preset::RAIN).wetness, 1.0f);
  EXPECT_EQ(look(Preset::CLEAR_NOON).wetness, 0.0f);
  EXPECT_LT(look(Preset::OVERCAST).sun.maxCoeff(), 0.5f * look(Preset::CLEAR_NOON).sun.maxCoeff());
  EXPECT_GT(look(Preset::OVERCAST).clouds, look(Preset::CLEAR_NOON).clouds);
  EXPECT_GT(look(Preset::DUSK).sun.x(), 1.5f * look(Preset::DUSK).sun.z()) << "warm light";
  EXPECT_EQ(look(Preset::NIGHT).lights, 1.0f);
  EXPECT_EQ(look(Preset::CLEAR_NOON).lights, 0.0f);
  const Look fast = LookOf(conditions::Of(Preset::CLEAR_NOON, Quality::kFast));
  EXPECT_FALSE(fast.full);
  EXPECT_FALSE(fast.shadows);
}

// Every camera of the urban map with every channel (urban_render_support.h),
// the street lanterns known to the renderer.
class LookRenderTest : public testing::UrbanRenderTest {
 protected:
  static void SetUpTestSuite() {
    UrbanRenderTest::SetUpTestSuite();
    renderer_->SetLamps(graphics_->lamps());
  }

  // Every channel of camera `index` in `conditions`.
  static Shot Render(std::size_t index, const conditions::Conditions& conditions) {
    return Render(index, LookOf(conditions));
  }
  static Shot Render(std::size_t index, const Look& look) {
    renderer_->SetLook(look);
    return UrbanRenderTest::Render(View(index));
  }
};

using testing::SameBytes;

double MeanLuma(const testing::RenderedFrame& frame) {
  double sum = 0;
  for (std::size_t i = 0; i < frame.rgb.size(); i += 3) {
    sum += 0.299 * frame.rgb[i] + 0.587 * frame.rgb[i + 1] + 0.114 * frame.rgb[i + 2];
  }
  return sum / static_cast<double>(frame.rgb.size() / 3);
}

TEST_F(LookRenderTest, GroundTruthIsByteIdenticalInEveryPresetAndQuality) {
  for (std::size_t camera = 0; camera < scene_->cameras.size(); ++camera) {
    SCOPED_TRACE(scene_->cameras[camera].name);
    const Shot reference = Render(camera, conditions::Of(Preset::CLEAR_NOON, Quality::kFast));
    ASSERT_GT(std::count_if(reference.unoccluded.begin(), reference.unoccluded.end(), [](uint32_t n) { return n > 0; }),
              0)
        << "the view shows labelled objects";
    std::vector<conditions::Conditions> all;
    for (const conditions::PresetInfo& info : conditions::kPresets) all.push_back(conditions::Of(info.preset));
    all.push_back({Preset::CLEAR_NOON, 7.0, Quality::kFull});
    all.push_back(conditions::Randomized(9, 3, conditions::Conditions{}));  // exposure and a colour jitter per object
    for (const conditions::Conditions& look : all) {
      SCOPED_TRACE(conditions::Describe(look));
      const Shot shot = Render(camera, look);
      EXPECT_TRUE(SameBytes(shot.frame.depth, reference.frame.depth));
      EXPECT_TRUE(SameBytes(shot.frame.mask, reference.frame.mask));
      EXPECT_TRUE(SameBytes(shot.frame.semantic, reference.frame.semantic));
      EXPECT_TRUE(SameBytes(shot.frame.normals, reference.frame.normals));
      EXPECT_TRUE(SameBytes(shot.frame.flow, reference.frame.flow));
      EXPECT_EQ(shot.unoccluded, reference.unoccluded);
      EXPECT_FALSE(SameBytes(shot.frame.rgb, reference.frame.rgb)) << "the full look differs from the fast one";
    }
  }
}

TEST_F(LookRenderTest, SensorNoiseIsUnbiasedOfTheAskedSizeAndRepeatsPerSeed) {
  conditions::Conditions noisy = conditions::Of(Preset::OVERCAST);
  const Shot clean = Render(0, noisy);
  noisy.noise_read = 4.0;
  noisy.noise_shot = 0.0;
  const Shot first = Render(0, noisy);
  const Shot again = Render(0, noisy);
  EXPECT_TRUE(SameBytes(first.frame.rgb, again.frame.rgb)) << "the same seed (frame and camera) repeats";
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < clean.frame.rgb.size(); ++i) {
    const double d = static_cast<double>(first.frame.rgb[i]) - clean.frame.rgb[i];
    sum += d;
    sum2 += d * d;
  }
  const double n = static_cast<double>(clean.frame.rgb.size());
  EXPECT_LT(std::abs(sum / n), 0.3) << "unbiased";
  EXPECT_NEAR(std::sqrt(sum2 / n), 4.0, 0.6) << "read noise of 4 levels";
  EXPECT_TRUE(SameBytes(first.frame.depth, clean.frame.depth));
  EXPECT_TRUE(SameBytes(first.frame.mask, clean.frame.mask));
  // Shot noise grows with the level: bright pixels scatter more than dark ones.
  noisy.noise_read = 0.0;
  noisy.noise_shot = 2.0;
  const Shot shot = Render(0, noisy);
  double dark = 0, bright = 0;
  int dark_n = 0, bright_n = 0;
  for (std::size_t i = 0; i < clean.frame.rgb.size(); ++i) {
    const double d = static_cast<double>(shot.frame.rgb[i]) - clean.frame.rgb[i];
    if (clean.frame.rgb[i] < 100) {
      dark += d * d;
      ++dark_n;
    } else if (clean.frame.rgb[i] > 170) {
      bright += d * d;
      ++bright_n;
    }
  }
  ASSERT_GT(dark_n, 100);
  ASSERT_GT(bright_n, 100);
  EXPECT_GT(bright / bright_n, 2.0 * dark / dark_n);
}

TEST_F(LookRenderTest, EveryPresetRendersTheSameRgbEveryTime) {
  for (const conditions::PresetInfo& info : conditions::kPresets) {
    SCOPED_TRACE(info.name);
    const Shot first = Render(0, conditions::Of(info.preset));
    Render(1, conditions::Of(Preset::NIGHT));  // another view and look in between
    const Shot again = Render(0, conditions::Of(info.preset));
    EXPECT_TRUE(SameBytes(first.frame.rgb, again.frame.rgb));
  }
}

// Albedo is the material the full look lights, before any light: the same
// bytes under every preset's sun, sky, fog and night lights; rain darkens
// only the wet ground (road, sidewalk, terrain, markings). Drawn without RGB
// beside it, it is the same too (the full look's programs draw it either way).
TEST_F(LookRenderTest, AlbedoIsTheSameUnderEveryLight) {
  const Shot noon = Render(0, conditions::Of(Preset::CLEAR_NOON));
  const auto wet_ground = [](uint8_t semantic) {
    return semantic <= 1 || semantic == 9 || semantic == 19 || semantic == 20;
  };
  for (const conditions::PresetInfo& info : conditions::kPresets) {
    SCOPED_TRACE(info.name);
    const Shot shot = Render(0, conditions::Of(info.preset));
    EXPECT_FALSE(info.preset != Preset::CLEAR_NOON && SameBytes(shot.frame.rgb, noon.frame.rgb)) << "RGB is lit anew";
    if (info.preset != Preset::RAIN) {
      EXPECT_TRUE(SameBytes(shot.frame.albedo, noon.frame.albedo));
      continue;
    }
    std::size_t darker = 0, ground = 0;
    for (std::size_t i = 0; i < noon.frame.semantic.size(); ++i) {
      for (std::size_t c = 3 * i; c < 3 * i + 3; ++c) {
        if (wet_ground(noon.frame.semantic[i])) {
          ASSERT_LE(shot.frame.albedo[c], noon.frame.albedo[c]) << "pixel " << i;
        } else {
          ASSERT_EQ(shot.frame.albedo[c], noon.frame.albedo[c]) << "pixel " << i;
        }
      }
      ground += wet_ground(noon.frame.semantic[i]) ? 1 : 0;
      darker += shot.frame.albedo[3 * i] < noon.frame.albedo[3 * i] ? 1 : 0;
    }
    EXPECT_GT(darker, ground / 2) << "most wet ground is darker";
  }
  testing::RenderedFrame alone(kWidth, kHeight);
  renderer_->SetLook(LookOf(conditions::Of(Preset::CLEAR_NOON)));
  renderer_->Render(View(0), graphics_->draw_items(), alone.Buffers(channels::Bit(proto::CHANNEL_ALBEDO)), {});
  EXPECT_TRUE(SameBytes(alone.albedo, noon.frame.albedo));
}

// The fixed casters' shadow depth is drawn once and reused while the map
// stays put: a moving car's shadow must still follow it, exactly as a
// renderer that never drew anything before would draw it.
TEST_F(LookRenderTest, CachedShadowsOfFixedCastersAgreeWithAFreshRenderer) {
  const conditions::Conditions morning = conditions::Of(Preset::CLEAR_MORNING);
  Render(0, morning);  // primes the cache for the UAV's view
  sim::State later = *state_;
  sim::Entity& car = later.entities.front();
  car.body.position += Eigen::Vector3d(0.6, 0.4, 0.0);  // the UAV (and its view) stays
  graphics_->Update(later);
  const Shot warm = Render(0, morning);
  Renderer fresh(graphics_->meshes(), kWidth, kHeight);
  fresh.SetLook(LookOf(morning));
  const Shot cold = UrbanRenderTest::Render(View(0), fresh);  // the UAV did not move
  graphics_->Update(*state_);
  EXPECT_TRUE(SameBytes(warm.frame.rgb, cold.frame.rgb));
}

// Each camera keeps its own fixed casters' depth (up to four): rendering the
// three cameras in turn, each reusing its own, draws what a fresh renderer does.
TEST_F(LookRenderTest, ShadowsCachedPerCameraAgreeWithAFreshRendererForEachCamera) {
  const conditions::Conditions morning = conditions::Of(Preset::CLEAR_MORNING);
  for (std::size_t i = 0; i < 3; ++i) Render(i, morning);  // primes each camera's entry
  sim::State later = *state_;
  later.entities.front().body.position += Eigen::Vector3d(0.6, 0.4, 0.0);  // the car moves, the UAV stays
  graphics_->Update(later);
  std::vector<Shot> warm;
  for (std::size_t i = 0; i < 3; ++i) warm.push_back(Render(i, morning));
  for (std::size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE(i);
    Renderer one_camera(graphics_->meshes(), kWidth, kHeight);
    one_camera.SetLook(LookOf(morning));
    const Shot cold = UrbanRenderTest::Render(View(i), one_camera);
    EXPECT_TRUE(SameBytes(warm[i].frame.rgb, cold.frame.rgb));
  }
  graphics_->Update(*state_);
}

TEST_F(LookRenderTest, StreetLanternsLightTheRoadAtNightOnly) {
  ASSERT_GT(graphics_->lamps().size(), 8u) << "the urban map has lanterns";
  const auto lit_against_unlit = [](const conditions::Conditions& conditions) {
    const Shot lit = Render(1, conditions);  // car_front, with the lanterns
    Renderer unlit(graphics_->meshes(), kWidth, kHeight);
    unlit.SetLook(LookOf(conditions));
    const Shot dark = UrbanRenderTest::Render(View(1), unlit);
    EXPECT_TRUE(SameBytes(lit.frame.depth, dark.frame.depth));
    return MeanLuma(lit.frame) - MeanLuma(dark.frame);
  };
  EXPECT_GT(lit_against_unlit(conditions::Of(Preset::NIGHT)), 1.0) << "pools of light on the road";
  EXPECT_EQ(lit_against_unlit(conditions::Of(Preset::CLEAR_NOON)), 0.0) << "off by day";
}

// The target car's own headlights light the road ahead of its first-person
// camera at night, and nothing by day; no other channel changes.
TEST_F(LookRenderTest, HeadlightsLightTheRoadAheadAtNightOnly) {
  ASSERT_FALSE(graphics_->headlights().empty());
  const auto lit_against_dark = [](const conditions::Conditions& conditions) {
    renderer_->SetHeadlights(graphics_->headlights());
    const Shot lit = Render(1, conditions);  // car_front
    renderer_->SetHeadlights({});
    const Shot dark = Render(1, conditions);
    EXPECT_TRUE(SameBytes(lit.frame.depth, dark.frame.depth));
    EXPECT_TRUE(SameBytes(lit.frame.mask, dark.frame.mask));
    // The road straight ahead: the middle third of the image's lower half.
    double lit_road = 0, dark_road = 0;
    for (std::size_t i = 0; i < lit.frame.semantic.size(); ++i) {
      const std::size_t row = i / kWidth, column = i % kWidth;
      if (row < kHeight / 2 || column < kWidth / 3 || column > 2 * kWidth / 3) continue;
      if (lit.frame.semantic[i] != static_cast<uint8_t>(SemanticClass::kRoad)) continue;
      lit_road += lit.frame.rgb[3 * i + 1];
      dark_road += dark.frame.rgb[3 * i + 1];
    }
    return lit_road / std::max(dark_road, 1.0);
  };
  EXPECT_GT(lit_against_dark(conditions::Of(Preset::NIGHT)), 1.3) << "the road ahead is lit";
  EXPECT_EQ(lit_against_dark(conditions::Of(Preset::CLEAR_NOON)), 1.0) << "off by day";
}

TEST_F(LookRenderTest, NightIsDarkerThanDuskAndDuskThanNoonAndRainDarkensTheRoad) {
  const std::size_t chase = 2;  // car_chase: road, sidewalks, houses and sky
  ASSERT_EQ(scene_->cameras[chase].name, "car_chase");
  const Shot noon = Render(chase, conditions::Of(Preset::CLEAR_NOON));
  const Shot dusk = Render(chase, conditions::Of(Preset::DUSK));
  const Shot night = Render(chase, conditions::Of(Preset::NIGHT));
  EXPECT_LT(MeanLuma(night.frame), 0.8 * MeanLuma(dusk.frame)) << "even with the lanterns lit";
  EXPECT_LT(MeanLuma(dusk.frame), MeanLuma(noon.frame));
  // The road seen from the UAV above it: wet asphalt is darker than the
  // same asphalt dry under the same sky.
  const auto road_luma = [](const Shot& shot) {
    double sum = 0;
    int count = 0;
    for (std::size_t i = 0; i < shot.frame.semantic.size(); ++i) {
      if (shot.frame.semantic[i] != static_cast<uint8_t>(SemanticClass::kRoad)) continue;
      sum += shot.frame.rgb[3 * i] + shot.frame.rgb[3 * i + 1] + shot.frame.rgb[3 * i + 2];
      ++count;
    }
    return count > 0 ? sum / count : -1.0;
  };
  Look dry_look = LookOf(conditions::Of(Preset::RAIN));
  dry_look.wetness = 0.0f;
  const Shot dry = Render(0, dry_look);
  const Shot wet = Render(0, conditions::Of(Preset::RAIN));
  ASSERT_GT(road_luma(dry), 0.0) << "the UAV sees road";
  EXPECT_LT(road_luma(wet), 0.85 * road_luma(dry));
}

// The colour jitter of domain randomisation is compiled into the materials only
// when the look has one (ChannelProgram::kVariation): with it every object's
// colour moves, without it the frame is the plain look's, byte for byte.
TEST_F(LookRenderTest, ColourJitterTintsTheRgbOnlyWhenTheLookHasOne) {
  const Look plain = LookOf(conditions::Of(Preset::CLEAR_NOON));
  Look jittered = plain;
  jittered.variation = 12345;
  const Shot first = Render(0, plain);
  const Shot tinted = Render(0, jittered);
  const Shot again = Render(0, plain);
  EXPECT_TRUE(SameBytes(first.frame.rgb, again.frame.rgb)) << "no jitter left behind by the jittered program";
  EXPECT_FALSE(SameBytes(first.frame.rgb, tinted.frame.rgb));
  EXPECT_TRUE(SameBytes(first.frame.mask, tinted.frame.mask));
}

TEST_F(LookRenderTest, FogHidesTheDistance) {
  const std::size_t front = 1;  // car_front: looks down the road to the horizon
  const Shot clear = Render(front, conditions::Of(Preset::OVERCAST));
  const Shot fog = Render(front, conditions::Of(Preset::FOG));
  // Far pixels (> 80 m) come close to the fog's colour: their spread shrinks.
  const auto far_spread = [](const Shot& shot) {
    double sum = 0, sum2 = 0;
    int count = 0;
    for (std::size_t i = 0; i < shot.frame.depth.size(); ++i) {
      if (!(shot.frame.depth[i] > 80.0f && std::isfinite(shot.frame.depth[i]))) continue;
      const double g = shot.frame.rgb[3 * i + 1];
      sum += g;
      sum2 += g * g;
      ++count;
    }
    const double mean = sum / count;
    return count > 50 ? std::sqrt(sum2 / count - mean * mean) : -1.0;
  };
  ASSERT_GT(far_spread(clear), 0.0) << "the view reaches past 80 m";
  EXPECT_LT(far_spread(fog), 0.5 * far_spread(clear));
}

}  // namespace
}  // namespace sim4cv::render
