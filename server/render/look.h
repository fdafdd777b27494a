// The parameters the shaders light a frame with, worked out from the
// conditions (protocol/conditions.h): sun, sky, ambient, fog, wetness,
// night lights, exposure. Plain data; no GL.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "protocol/conditions.h"

namespace sim4cv::render {

struct Look {
  bool full = true;                 // false: the flat look of --quality fast
  bool shadows = true;              // a shadow map from the sun
  Eigen::Vector3f to_sun{0, 0, 1};  // unit, world (z up); the moon at night
  Eigen::Vector3f sun{1, 1, 1};     // linear irradiance of direct light
  Eigen::Vector3f sky_zenith{0.2f, 0.4f, 0.8f}, sky_horizon{0.6f, 0.7f, 0.8f};  // linear radiance
  Eigen::Vector3f ambient_sky{0.3f, 0.35f, 0.4f}, ambient_ground{0.15f, 0.13f, 0.1f};
  Eigen::Vector3f fog_colour{0.6f, 0.65f, 0.7f};
  float fog_density = 0.0f;   // per metre (Beer-Lambert)
  float clouds = 0.2f;        // cloud cover 0..1
  float wetness = 0.0f;       // 0 dry .. 1 puddled
  float lights = 0.0f;        // lit windows, lanterns and car lights, 0..1
  float exposure = 1.0f;      // multiplies radiance before tone mapping
  uint32_t variation = 0;     // 0: none; else the seed of a colour jitter per object (domain randomisation)
  float noise_read = 0.0f;    // sensor noise: read noise, standard deviation in 8-bit levels
  float noise_shot = 0.0f;    // ... shot noise: variance = noise_shot * level
};

// The look of `conditions`; the sun follows the hour (east at 6, south at
// noon, west at 18; at most 65 degrees high), whatever the preset.
Look LookOf(const conditions::Conditions& conditions);

}  // namespace sim4cv::render
