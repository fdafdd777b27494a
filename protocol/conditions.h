// The weather and time-of-day presets, listed once. The daemon's
// --conditions flag, Configure.set_conditions, run logs, dataset metadata,
// the renderer's look (server/render/look.cpp) and the docs read this table.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <string_view>

namespace sim4cv::conditions {

// X(ENUM, name, hour, what it looks like): hour is the preset's time of
// day (0..24, local solar time) unless a client or --hour overrides it.
#define SIM4CV_CONDITIONS(X)                                                                        \
  X(CLEAR_NOON, "clear_noon", 12.5, "high sun, short hard shadows, blue sky")                       \
  X(CLEAR_MORNING, "clear_morning", 7.5, "low warm sun from the east, long shadows")               \
  X(OVERCAST, "overcast", 12.0, "no direct sun, soft shadowless light, grey sky")                  \
  X(FOG, "fog", 10.0, "overcast with fog, visibility about 80 m")                                   \
  X(DUSK, "dusk", 17.8, "sun on the horizon, orange sky, dim light")                                \
  X(NIGHT, "night", 23.0, "dark sky, moonlight, street lanterns and car lights")                   \
  X(RAIN, "rain", 15.0, "overcast, wet dark asphalt that mirrors the sky, light haze")

enum class Preset {
#define SIM4CV_CONDITIONS_ENUM(ENUM, ...) ENUM,
  SIM4CV_CONDITIONS(SIM4CV_CONDITIONS_ENUM)
#undef SIM4CV_CONDITIONS_ENUM
};

struct PresetInfo {
  Preset preset;
  std::string_view name;  // in --conditions, Configure and logs
  double hour;
  std::string_view summary;
};

#define SIM4CV_CONDITIONS_INFO(ENUM, NAME, HOUR, SUMMARY) PresetInfo{Preset::ENUM, NAME, HOUR, SUMMARY},
inline constexpr std::array kPresets = {SIM4CV_CONDITIONS(SIM4CV_CONDITIONS_INFO)};
#undef SIM4CV_CONDITIONS_INFO

inline constexpr double kMinHour = 0.0;
inline constexpr double kMaxHour = 24.0;

inline const PresetInfo& Info(Preset preset) { return kPresets[static_cast<std::size_t>(preset)]; }

inline std::optional<Preset> FindByName(std::string_view name) {
  for (const PresetInfo& info : kPresets) {
    if (info.name == name) return info.preset;
  }
  return std::nullopt;
}

// "clear_noon, clear_morning, ...": for error messages and --help.
inline std::string Names() {
  std::string names;
  for (const PresetInfo& info : kPresets) {
    if (!names.empty()) names += ", ";
    names += info.name;
  }
  return names;
}

// What the world looks like: a preset, its time of day, and how much of the
// look is drawn. Plain data, so the sim thread, logs and the renderer share it.
enum class Quality { kFast, kFull };

struct Conditions {
  Preset preset = Preset::CLEAR_NOON;
  double hour = Info(Preset::CLEAR_NOON).hour;
  Quality quality = Quality::kFull;
  double exposure = 1.0;   // multiplies the preset's exposure
  uint32_t variation = 0;  // 0: every surface its own colour; else the seed of a colour jitter per object
  // Sensor noise of the full look, off (0) by default: read noise (standard
  // deviation in 8-bit levels) and shot noise (variance = gain * level).
  double noise_read = 0.0, noise_shot = 0.0;
};

inline constexpr double kMaxNoiseRead = 50.0;  // levels
inline constexpr double kMaxNoiseShot = 10.0;

// The preset at its own hour.
inline Conditions Of(Preset preset, Quality quality = Quality::kFull) {
  return Conditions{preset, Info(preset).hour, quality};
}

inline std::string_view QualityName(Quality quality) { return quality == Quality::kFast ? "fast" : "full"; }

inline std::optional<Quality> FindQuality(std::string_view name) {
  if (name == "fast") return Quality::kFast;
  if (name == "full") return Quality::kFull;
  return std::nullopt;
}

// "rain at 15.00 h, full quality" (plus ", exposure 1.20, variation 77"
// when set): for logs and run-log headers.
inline std::string Describe(const Conditions& conditions) {
  char text[64];
  std::snprintf(text, sizeof text, " at %.2f h, ", conditions.hour);
  std::string description = std::string(Info(conditions.preset).name) + text +
                            std::string(QualityName(conditions.quality)) + " quality";
  if (conditions.exposure != 1.0 || conditions.variation != 0) {
    std::snprintf(text, sizeof text, ", exposure %.2f, variation %u", conditions.exposure, conditions.variation);
    description += text;
  }
  if (conditions.noise_read != 0.0 || conditions.noise_shot != 0.0) {
    std::snprintf(text, sizeof text, ", noise read %.2f shot %.2f", conditions.noise_read, conditions.noise_shot);
    description += text;
  }
  return description;
}

// Domain randomisation: draw number `draw` of the sequence `seed` gives
// (the same conditions for the same seed and draw, on any machine): a
// preset, an hour that suits it, an exposure in [0.7, 1.4] and a colour
// variation seed; `base`'s quality and sensor noise stay.
inline Conditions Randomized(uint64_t seed, uint64_t draw, const Conditions& base) {
  uint64_t state = seed ^ (draw * 0x9E3779B97F4A7C15ull);
  const auto next = [&state] {  // splitmix64
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  };
  const auto uniform = [&next](double low, double high) {
    return low + (high - low) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  };
  Conditions conditions = base;  // its quality and noise stay
  conditions.preset = kPresets[next() % kPresets.size()].preset;
  switch (conditions.preset) {
    case Preset::CLEAR_MORNING: conditions.hour = next() % 2 ? uniform(6.8, 9.0) : uniform(15.0, 17.0); break;
    case Preset::DUSK: conditions.hour = uniform(17.3, 17.9); break;  // the sun sets (look.h) at about 17.93
    case Preset::NIGHT: conditions.hour = std::fmod(uniform(20.0, 28.5), 24.0); break;
    case Preset::FOG: conditions.hour = uniform(7.0, 12.0); break;
    default: conditions.hour = uniform(9.0, 16.0); break;
  }
  conditions.exposure = uniform(0.7, 1.4);
  conditions.variation = static_cast<uint32_t>(next() | 1u);
  return conditions;
}

}  // namespace sim4cv::conditions
