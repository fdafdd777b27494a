// How the renderer produces one pixel channel: its render target, how it is
// cleared and read back, and the GLSL that writes it. One file per channel in
// channels/ defines one of these; channel_outputs.cpp lists them in the
// order of protocol/channels.h, which says what the channel is on the wire.
#pragma once

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <array>
#include <cstdint>

#include "protocol/channels.h"

namespace sim4cv::render {

struct ChannelOutput {
  proto::Channel channel;
  GLenum target_format;           // renderbuffer internal format
  GLenum read_format, read_type;  // glReadPixels into the channel's wire layout
  bool integer;                   // an integer target (cleared with glClearBufferuiv)
  std::array<GLfloat, 4> clear_float;   // where nothing is drawn, for float targets
  std::array<GLuint, 4> clear_integer;  // ... and for integer targets
  const char* glsl_type;          // the fragment output's type, e.g. "vec2"
  // Statements that assign OUT from the inputs every channel may read
  // (renderer.cpp, kFragmentInputs): v_color, v_world_normal,
  // v_camera_normal, v_world_position, v_depth, v_semantic,
  // v_previous_clip, u_instance, u_to_light, u_viewport.
  const char* glsl_body;
  // GLSL declared before main() when this channel is drawn (functions and
  // their uniforms, e.g. shading.h); null: none.
  const char* glsl_functions = nullptr;
  // Its GLSL has a full-look variant (#ifdef SIM4CV_FULL_LOOK) reading the
  // look's uniforms (shading.h): with the full look it is drawn by the
  // full look's programs whether or not RGB is drawn beside it.
  bool reads_look = false;
};

// One per entry of channels::kPixelChannels, in that order.
extern const std::array<const ChannelOutput*, channels::kPixelChannelCount> kChannelOutputs;

}  // namespace sim4cv::render
