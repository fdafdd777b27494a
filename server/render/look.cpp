#include "server/render/look.h"

#include <algorithm>
#include <cmath>

namespace sim4cv::render {
namespace {

using conditions::Preset;
using Eigen::Vector3f;

constexpr float kPi = 3.14159265f;
constexpr float kHighestSunDeg = 65.0f;

// Where the sun is at `hour`: it rises in the east (+x) at 6, stands south
// (-y) at noon and sets in the west at 18; below the horizon at night.
Vector3f SunDirection(double hour) {
  const float day_angle = static_cast<float>((hour - 6.0) / 12.0) * kPi;  // 0 at sunrise, pi at sunset
  const float elevation = std::sin(day_angle) * kHighestSunDeg * kPi / 180.0f;
  const float azimuth = day_angle;  // from east through south to west
  return Vector3f(std::cos(azimuth) * std::cos(elevation), -std::sin(azimuth) * std::cos(elevation),
                  std::sin(elevation))
      .normalized();
}

// Daylight colour by sun elevation: white high, orange near the horizon.
Vector3f SunColour(float elevation_sin) {
  const float warm = std::clamp(1.0f - elevation_sin * 2.5f, 0.0f, 1.0f);
  return Vector3f(1.0f, 0.95f, 0.88f) * (1.0f - warm) + Vector3f(1.0f, 0.55f, 0.25f) * warm;
}

}  // namespace

Look LookOf(const conditions::Conditions& conditions) {
  Look look;
  look.full = conditions.quality == conditions::Quality::kFull;
  Vector3f sun = SunDirection(conditions.hour);
  const bool night = sun.z() < 0.02f;
  if (night) {  // the moon, opposite in azimuth and 40 degrees up
    sun = Vector3f(-sun.x(), -sun.y(), 0.0f).normalized() * std::cos(0.7f) + Vector3f(0, 0, std::sin(0.7f));
  }
  look.to_sun = sun.normalized();
  const float height = std::max(look.to_sun.z(), 0.0f);
  const float day = night ? 0.0f : std::clamp(height * 4.0f, 0.0f, 1.0f);  // twilight fades in
  look.sun = night ? Vector3f(0.05f, 0.06f, 0.09f) : SunColour(height) * 2.2f * day;
  look.sky_zenith = Vector3f(0.012f, 0.015f, 0.03f) * (1 - day) + Vector3f(0.15f, 0.32f, 0.75f) * day;
  look.sky_horizon = Vector3f(0.02f, 0.025f, 0.04f) * (1 - day) + Vector3f(0.62f, 0.72f, 0.85f) * day;
  look.ambient_sky = Vector3f(0.02f, 0.025f, 0.04f) * (1 - day) + Vector3f(0.45f, 0.55f, 0.75f) * day;
  look.ambient_ground = look.ambient_sky.cwiseProduct(Vector3f(0.45f, 0.4f, 0.33f));
  look.fog_colour = look.sky_horizon;
  look.fog_density = 0.0008f;  // a little aerial perspective at every hour (visibility ~4 km)
  look.lights = 1.0f - day;
  look.exposure = night ? 1.5f : 0.85f / (0.45f + 0.55f * day);
  look.clouds = 0.25f;

  bool sunny = !night;
  const auto overcast = [&](float amount) {
    sunny = false;  // what little direct light is left casts no sharp shadows
    look.sun *= 1.0f - amount;
    const Vector3f grey = Vector3f(0.55f, 0.57f, 0.6f) * std::max(day, 0.05f);
    look.sky_zenith = look.sky_zenith * (1 - amount) + grey * amount;
    look.sky_horizon = look.sky_horizon * (1 - amount) + grey * 1.1f * amount;
    look.ambient_sky = look.ambient_sky * (1 - amount) + grey * 1.6f * amount;
    look.fog_colour = look.sky_horizon;
    look.clouds = 0.25f + 0.75f * amount;
  };
  switch (conditions.preset) {
    case Preset::CLEAR_NOON:
    case Preset::CLEAR_MORNING:
      break;
    case Preset::OVERCAST:
      overcast(0.85f);
      break;
    case Preset::FOG:
      overcast(0.9f);
      look.fog_density = 0.03f;  // visibility (3/density) about 100 m
      break;
    case Preset::DUSK:
      look.sky_horizon = look.sky_horizon.cwiseProduct(Vector3f(1.6f, 0.9f, 0.6f));
      look.fog_colour = look.sky_horizon;
      break;
    case Preset::NIGHT:
      look.lights = 1.0f;
      break;
    case Preset::RAIN:
      overcast(0.8f);
      look.wetness = 1.0f;
      look.fog_density = 0.003f;  // visibility ~1 km
      break;
  }
  look.shadows = look.full && sunny && day > 0.2f;
  look.exposure *= static_cast<float>(conditions.exposure);
  look.variation = conditions.variation;
  look.noise_read = static_cast<float>(conditions.noise_read);
  look.noise_shot = static_cast<float>(conditions.noise_shot);
  return look;
}

}  // namespace sim4cv::render
