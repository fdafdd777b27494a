// GLSL shared by the RGB and albedo channels and the sky pass: the look's uniforms,
// value noise, the sky, procedural materials per semantic class, sun
// shadows and the camera's response. Every pattern is a function of the
// world position and the class only (no textures, no time, no randomness),
// so a frame is a pure function of the scene, the camera and the look.
#pragma once

namespace sim4cv::render {

inline constexpr const char* kShadingGlsl = R"(
uniform vec3 u_sun;              // direct light, linear
uniform vec3 u_sky_zenith;
uniform vec3 u_sky_horizon;
uniform vec3 u_ambient_sky;      // hemisphere light from above ...
uniform vec3 u_ambient_ground;   // ... and from below
uniform vec4 u_fog;              // rgb: colour; a: density per metre
uniform vec4 u_weather;          // x: clouds, y: wetness, z: night lights, w: exposure
uniform vec3 u_camera_position;  // world
uniform mat4 u_shadow_from_world;  // to the shadow map's [0,1]^3
uniform sampler2DShadow u_shadow_map;
uniform uint u_variation;          // the seed of a colour jitter per object, with SIM4CV_VARIATION
uniform vec2 u_noise;              // sensor noise: read sigma, shot gain, in [0, 1] units; 0, 0: none
uniform uint u_noise_seed;         // per frame and camera
uniform vec3 u_lamps[4];           // Renderer::kMaxLamps street lanterns nearest the view (world), with SIM4CV_LAMPS
uniform int u_lamp_count;
uniform vec3 u_headlights[2];      // Renderer::kMaxHeadlights cars' headlights nearest the view (world)
uniform vec3 u_headlight_directions[2];
uniform int u_headlight_count;

// Integer hashing: a few SIMD integer ops per value where a float hash
// takes about twenty (llvmpipe pays per instruction).
const uint kHashX = 0x8da6b343u, kHashY = 0xd8163841u;
uint Mix(uint h) {
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  return h ^ (h >> 16);
}
float HashU(uint h) { return float(Mix(h) >> 8) * (1.0 / 16777216.0); }

// Domain randomisation's colour jitter: each labelled object (by instance)
// and each class of unlabelled surface (road, grass...) gets its own tint,
// the same in every frame of one u_variation.
vec3 Vary(vec3 base, uint semantic) {
#ifndef SIM4CV_VARIATION  // u_variation 0: no jitter, and no code for it
  return base;
#else
  uint h = Mix((u_instance != 0u ? u_instance : semantic + 65536u) * 0x9e3779b9u ^ u_variation);
  vec3 jitter = vec3(uvec3(h, h >> 8, h >> 16) & 255u) / 255.0;
  return clamp(base * (0.65 + 0.7 * jitter), 0.0, 1.0);
#endif
}
// A value in [0, 1) per integer cell; `cell` holds whole numbers (floor()).
float Hash(vec2 cell) {
  uvec2 u = uvec2(ivec2(cell));
  return HashU(u.x * kHashX + u.y * kHashY);
}
// Value noise: the cell corners' hashes, smoothly interpolated.
float Noise(vec2 p) {
  vec2 i = floor(p), f = p - i;
  vec2 w = f * f * (3.0 - 2.0 * f);
  uvec2 u = uvec2(ivec2(i));
  uint corner = u.x * kHashX + u.y * kHashY;
  return mix(mix(HashU(corner), HashU(corner + kHashX), w.x),
             mix(HashU(corner + kHashY), HashU(corner + kHashX + kHashY), w.x), w.y);
}
float Fbm(vec2 p) {
  return (0.5 * Noise(p) + 0.25 * Noise(p * 2.03 + 17.0) + 0.125 * Noise(p * 4.01 + 31.0)) / 0.875;
}

vec3 Sky(vec3 d) {
  vec3 sky = mix(u_sky_horizon, u_sky_zenith, sqrt(clamp(d.z, 0.0, 1.0)));
  if (d.z < 0.0) sky = u_sky_horizon * 0.8;
  float toward_sun = max(dot(d, u_to_light), 0.0);
  sky += u_sun * (smoothstep(0.9996, 0.9999, toward_sun) * 6.0 + pow(toward_sun, 48.0) * 0.25);
  if (d.z > 0.005) {
    vec2 layer = d.xy / (d.z + 0.08) * 1.5;
    float cover = smoothstep(1.0 - u_weather.x, 1.25 - u_weather.x, Fbm(layer));
    vec3 cloud = u_ambient_sky * 1.1 + u_sun * 0.35;
    sky = mix(sky, cloud, cover * smoothstep(0.005, 0.12, d.z));
  }
  return sky;
}

// Radiance at the camera -> gamma-encoded colour: fog (0 none .. 1 only
// fog), exposure, a soft shoulder instead of clipping (Reinhard), then
// gamma 2 (a square root: llvmpipe pays per instruction, and pow is many).
vec4 Expose(vec3 radiance, float fog) {
  vec3 c = mix(radiance, u_fog.rgb, fog) * u_weather.w * 1.4;
  c = sqrt(c / (1.0 + c));
#ifdef SIM4CV_SENSOR_NOISE
  // Shot + read noise per pixel and channel, seeded by the frame and the
  // pixel: sigma^2 = read^2 + shot * level. Four uniform hashes summed are
  // close enough to a Gaussian (Irwin-Hall, variance 1/3 -> scaled to 1).
  uvec2 pixel = uvec2(gl_FragCoord.xy);
  uint h = Mix(pixel.x * kHashX ^ pixel.y * kHashY ^ u_noise_seed * 0x27d4eb2fu);
  vec3 gauss = vec3(0.0);
  for (int i = 0; i < 4; ++i) {
    h = Mix(h + uint(i));
    gauss += vec3(uvec3(h, h >> 10, h >> 20) & 1023u) / 1023.0;
  }
  gauss = (gauss - 2.0) * 1.7320508;
  c += gauss * sqrt(u_noise.x * u_noise.x + u_noise.y * c);
#endif
  return vec4(c, 1.0);
}

// Compiled in only with shadows (SIM4CV_SHADOWS): llvmpipe would sample
// the map for every pixel even behind a branch, and sampling is its dearest step.
float SunVisibility(vec3 p, vec3 n) {
#ifndef SIM4CV_SHADOWS
  return 1.0;
#else
  vec3 s = (u_shadow_from_world * vec4(p + n * 0.06, 1.0)).xyz;
  vec2 edge = min(s.xy, 1.0 - s.xy);
  float inside = min(edge.x, edge.y);
  if (inside <= 0.0) return 1.0;
  // One nearest tap: four taps or linear filtering cost more than the rest of the shading.
  return mix(1.0, texture(u_shadow_map, s), smoothstep(0.0, 0.05, inside));  // fades out at the map's edge
#endif
}

// The sky as a mirror shows it: the gradient only (no clouds or sun disc,
// which Sky() adds for the sky itself).
vec3 SkyReflection(vec3 d) { return mix(u_sky_horizon, u_sky_zenith, sqrt(clamp(d.z, 0.0, 1.0))); }

struct Surface {
  vec3 albedo;
  float specular;     // sun highlight strength
  float shininess;
  float reflectance;  // Fresnel reflectance at normal incidence
  float mirror;       // how much of the surface is smooth enough to mirror the sky, 0..1
  vec3 emission;
};

// llvmpipe runs every branch of a fragment shader for every pixel (masked
// SIMD), so the materials share one evaluation of the noise: each class only
// chooses its scales and how the pattern is used, with cheap selects.
// Per class: x: blotch frequency (1/m), y: blotch amplitude, z: grain
// frequency, w: grain amplitude.
vec4 PatternOf(uint c) {
  if (c == 0u || c == 19u || c == 20u) return vec4(0.35, 0.45, 25.0, 0.15);  // asphalt and paint
  if (c == 1u) return vec4(0.5, 0.15, 2.0, 0.25);                            // 0.5 m sidewalk tiles
#ifdef SIM4CV_FLAT_GROUND
  return vec4(0.12, 0.6, 3.0, 0.2);  // the only flat ground class left: terrain (9)
#endif
  if (c == 9u) return vec4(0.12, 0.6, 3.0, 0.2);                             // grass, sand
  if (c == 8u) return vec4(2.3, 0.9, 6.0, 0.3);                              // leaves
  if (c == 2u) return vec4(0.5, 0.3, 4.0, 0.1);                              // plaster
  if (c == 11u || c == 12u) return vec4(4.0, 0.3, 9.0, 0.1);                 // cloth
  return vec4(0.8, 0.1, 8.0, 0.05);
}

Surface Material(uint c, vec3 base, vec3 p, vec3 n, float distance) {
  Surface s = Surface(base, 0.04, 8.0, 0.04, 0.0, vec3(0.0));
  bool flat_ground = c == 0u || c == 1u || c == 9u || c == 19u || c == 20u;
  bool vertical = abs(n.z) < 0.3;
  // Coordinates in the surface: the ground's x, y; a wall's along-wall and height.
  vec2 along = normalize(vec2(-n.y, n.x) + vec2(1e-5, 0.0));
  vec2 q = vertical ? vec2(dot(p.xy, along), p.z) : p.xy + vec2(p.z * 0.7, -p.z * 0.4);
  vec4 pattern = PatternOf(c);
  float detail = 1.0 - smoothstep(60.0, 160.0, distance);  // no pattern finer than a pixel far away
  float blotch = Noise(q * pattern.x);
  float grain = Hash(floor(q * pattern.z));
  s.albedo = base * (1.0 + (pattern.y * (blotch - 0.5) + pattern.w * (grain - 0.5)) * detail);
  if (c == 1u) {  // grout between tiles
    vec2 joint = abs(fract(q * pattern.z) - 0.5);
    s.albedo *= 1.0 - 0.35 * step(0.46, max(joint.x, joint.y)) * detail;
  }
  if (c == 19u || c == 20u) {  // paint worn down to asphalt in patches
    s.albedo = mix(s.albedo, vec3(0.06, 0.06, 0.065), smoothstep(0.6, 0.8, blotch) * 0.7 * detail);
  }
  if (c == 9u && base.r > base.g) {  // sand: ripples across the wind
    s.albedo *= 1.0 + 0.1 * sin(p.x * 2.2 + p.y * 0.7 + 4.0 * blotch) * detail;
  }
// Flat ground (Renderer's FlatGround classes: 0, 1, 9, 19, 20) is drawn by
// a program of its own without the other classes' materials: most pixels
// are ground, and llvmpipe would run every class's code for each of them.
#ifndef SIM4CV_FLAT_GROUND
  if (c >= 13u && c <= 18u) {  // vehicle paint: clear coat
    s.specular = 1.2;
    s.shininess = 80.0;
    s.reflectance = 0.05;
    s.mirror = 0.5;
  }
  if (c == 5u || c == 6u || c == 7u || c == 21u) {  // metal
    s.specular = 0.6;
    s.shininess = 40.0;
    s.mirror = 0.3;
  }
  if (c == 2u && vertical) {  // facades: storeys and bays of windows; the style changes per 24 m block
    vec2 block = floor(p.xy / 24.0);
    float style = Hash(block);
    vec2 bay = vec2(2.6 + 1.6 * fract(style * 13.7), 3.0 + 0.6 * fract(style * 71.3));
    vec2 window_cell = q / bay;
    vec2 half_size = style < 0.33 ? vec2(0.3, 0.28) : style < 0.66 ? vec2(0.38, 0.22) : vec2(0.22, 0.34);
    vec2 off = abs(fract(window_cell) - vec2(0.5, 0.55));
    s.albedo *= 1.0 - 0.25 * step(fract(window_cell.y), 0.06);  // ledges
    if (off.x < half_size.x && off.y < half_size.y && p.z > 0.9) {
      s.albedo = vec3(0.03, 0.035, 0.04);
      s.reflectance = 0.1;
      s.mirror = 1.0;
      s.specular = 1.0;
      s.shininess = 96.0;
      s.emission = vec3(1.0, 0.75, 0.45) * step(0.55, Hash(floor(window_cell) + block * 31.0)) * u_weather.z * 0.6;
    }
  }
#endif
  if (flat_ground) {
    s.reflectance = 0.03;
#ifdef SIM4CV_WET
    // wet: darker, and puddles that mirror the sky
    float wet = u_weather.y;
    float puddle = (c == 0u) ? smoothstep(0.62, 0.75, blotch) : 0.0;
    s.albedo *= 1.0 - (c == 9u ? 0.3 : 0.6) * wet;
    s.mirror = wet * (0.3 + 0.6 * puddle);
    s.specular = 0.1 + wet * 2.0;
    s.shininess = 24.0 + wet * 200.0;
#else
    // dry (the look's wetness 0): the wet branch's values at wet = 0, a mirror of 0
    s.specular = 0.1;
    s.shininess = 24.0;
#endif
  }
  return s;
}

// The surface at world point p with unit normal n, before any light: the
// material RGB lights, and all the albedo channel shows.
Surface SurfaceAt(vec3 base, vec3 n, vec3 p, uint semantic) {
  return Material(semantic, Vary(base, semantic), p, n, length(u_camera_position - p));
}

// fog: 0 (none) .. 1 (only fog), interpolated from the vertices (the
// vertex shader's v_fog: exp(-density * distance) is smooth enough).
vec4 ShadeFull(vec3 base, vec3 world_normal, vec3 p, uint semantic_and_flags, float fog) {
  uint semantic = semantic_and_flags & 255u;
  vec3 n = normalize(world_normal);
  vec3 to_eye_full = u_camera_position - p;
  vec3 to_eye = to_eye_full / length(to_eye_full);
  Surface s = SurfaceAt(base, n, p, semantic);
  float direct = max(dot(n, u_to_light), 0.0) * SunVisibility(p, n);
  vec3 ambient = mix(u_ambient_ground, u_ambient_sky, 0.5 + 0.5 * n.z);
  vec3 half_way = normalize(u_to_light + to_eye);
  // Blinn-Phong, with x^k as exp2(k (x - 1) / ln 2): one transcendental instead of pow's two.
  float highlight = exp2(s.shininess * 1.4427 * (max(dot(n, half_way), 0.0) - 1.0));
  vec3 light = ambient + u_sun * direct;
#ifdef SIM4CV_LAMPS
  // Street lanterns: warm point lights, inverse-square with a window that
  // ends at 18 m (pools of light under each lantern), scaled by the look's
  // night lights.
  for (int i = 0; i < u_lamp_count; ++i) {
    vec3 to_lamp = u_lamps[i] - p;
    float d2 = dot(to_lamp, to_lamp);
    float window = max(1.0 - d2 / 324.0, 0.0);
    light += vec3(1.0, 0.78, 0.5) *
             (20.0 * u_weather.z * max(dot(n, to_lamp), 0.0) * inversesqrt(d2) * window * window / (d2 + 1.0));
  }
  // Headlights: cold-white beams aimed a little down the road, brightest
  // on their axis (where the road is met at a grazing angle, 20-40 m ahead)
  // and reaching 50 m; the near road gets the beam's dimmer edge.
  for (int i = 0; i < u_headlight_count; ++i) {
    vec3 to_car = u_headlights[i] - p;
    float d2 = dot(to_car, to_car);
    vec3 l = to_car * inversesqrt(d2);
    float axis = -dot(l, u_headlight_directions[i]);
    float beam = clamp((axis - 0.9) * 10.0, 0.0, 1.0);
    beam *= beam * beam;  // a hot centre, a dim edge
    float window = max(1.0 - d2 / 2500.0, 0.0);
    light += vec3(1.0, 0.96, 0.88) * (40.0 * u_weather.z * max(dot(n, l), 0.0) * beam * window * window / (1.0 + 0.02 * d2));
  }
#endif
  // Lamps and headlights (kEmissive) glow with their own colour at night.
  vec3 glow = (semantic_and_flags & 256u) != 0u ? base * (4.0 * u_weather.z) : vec3(0.0);
  vec3 c = s.albedo * light + u_sun * (direct * s.specular * highlight) + s.emission + glow;
#if defined(SIM4CV_WET) || !defined(SIM4CV_FLAT_GROUND)  // dry flat ground mirrors nothing (mirror 0)
  // Schlick's Fresnel: the sky shows most at grazing angles.
  float grazing = 1.0 - max(dot(n, to_eye), 0.0);
  float grazing2 = grazing * grazing;
  float fresnel = s.reflectance + (1.0 - s.reflectance) * grazing2 * grazing2 * grazing;
  c = mix(c, SkyReflection(reflect(-to_eye, n)), fresnel * s.mirror);
#endif
  return Expose(c, fog);
}
)";

}  // namespace sim4cv::render
