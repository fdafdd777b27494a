// The GL program that draws one set of pixel channels in one pass (multiple
// render targets): a shared vertex shader and a fragment shader composed from
// the ChannelOutput of each channel in the set, output i going to colour
// attachment i. Channels nobody asked for are not in the shader, so they cost
// no fragment work. Needs a current GL context.
#pragma once

#include <cstdint>

#include "server/render/channel_output.h"
#include "server/render/look_uniforms.h"

namespace sim4cv::render {

// Bit i: plane i of channels::kPixelChannels.
using PlaneSet = uint32_t;

class ChannelProgram {
 public:
  // How RGB is drawn, as compile-time switches of the GLSL (llvmpipe would
  // pay for a uniform branch's untaken side): the full look (else the
  // fast one), and in the full look sun shadows, sensor noise and lanterns;
  // kFlatGround: the full look's program for flat ground only (road, sidewalk,
  // terrain, markings), without the other classes' materials; kWet: the full
  // look's wet ground (darker, puddles mirroring the sky), left out when dry;
  // kVariation: domain randomisation's colour jitter per object.
  enum RgbLook : uint32_t {
    kFast = 0,
    kFull = 1,
    kShadows = 2,
    kNoise = 4,
    kLamps = 8,
    kFlatGround = 16,
    kWet = 32,
    kVariation = 64
  };
  inline static constexpr uint32_t kRgbLooks = 128;  // every combination of the bits
  ChannelProgram(PlaneSet planes, uint32_t look);
  ~ChannelProgram();
  ChannelProgram(const ChannelProgram&) = delete;
  ChannelProgram& operator=(const ChannelProgram&) = delete;

  GLuint id() const { return program_; }
  PlaneSet planes() const { return planes_; }

  // Uniform locations; -1 where the linker found the uniform unused for this
  // set (glUniform* ignores -1).
  GLint u_model = -1, u_view = -1, u_projection = -1, u_normal_matrix = -1, u_instance = -1, u_to_light = -1;
  GLint u_previous_model = -1, u_previous_view_projection = -1, u_viewport = -1;
  LookUniforms look;  // those of shading.h, where a channel (RGB, albedo) uses them
  GLint u_lamps = -1, u_lamp_count = -1, u_headlights = -1, u_headlight_directions = -1, u_headlight_count = -1;

 private:
  PlaneSet planes_ = 0;
  GLuint program_ = 0;
};

}  // namespace sim4cv::render
