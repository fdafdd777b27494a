#include "server/render/channel_program.h"

#include <algorithm>
#include <array>
#include <string>

#include "server/render/gl_program.h"

namespace sim4cv::render {
namespace {

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_color;
layout(location = 3) in uint a_semantic;
uniform mat4 u_model;
uniform mat4 u_view;
uniform mat4 u_projection;
uniform mat3 u_normal_matrix;
uniform mat4 u_previous_model;
uniform mat4 u_previous_view_projection;
uniform vec4 u_fog;  // the full look's fog (look.h): a is its density per metre
out vec3 v_world_normal;
out vec3 v_world_position;
out vec3 v_camera_normal;
out vec3 v_color;
out float v_depth;
flat out uint v_semantic;
out vec4 v_previous_clip;
out float v_fog;
void main() {
  vec4 world_position = u_model * vec4(a_position, 1.0);
  vec4 camera_position = u_view * world_position;
  v_world_position = world_position.xyz;
  v_fog = 1.0 - exp(-u_fog.a * length(camera_position.xyz));
  v_depth = -camera_position.z;  // camera-space z is affine over a triangle, so interpolation is exact
  v_world_normal = u_normal_matrix * a_normal;
  v_camera_normal = mat3(u_view) * v_world_normal;  // the view is rigid: its 3x3 part rotates
  v_color = a_color;
  v_semantic = a_semantic;
  v_previous_clip = u_previous_view_projection * (u_previous_model * vec4(a_position, 1.0));
  gl_Position = u_projection * camera_position;
}
)";

// What every channel's glsl_body may read (channel_output.h).
constexpr const char* kFragmentInputs = R"(#version 330 core
in vec3 v_world_normal;
in vec3 v_world_position;
in vec3 v_camera_normal;
in vec3 v_color;
in float v_depth;
flat in uint v_semantic;
in vec4 v_previous_clip;
in float v_fog;
uniform uint u_instance;
uniform vec3 u_to_light;
uniform vec2 u_viewport;
)";

std::string FragmentShader(PlaneSet planes, uint32_t look) {
  std::string declarations = kFragmentInputs;
  const std::size_t after_version = declarations.find('\n') + 1;
  if (look & ChannelProgram::kNoise) declarations.insert(after_version, "#define SIM4CV_SENSOR_NOISE\n");
  if (look & ChannelProgram::kLamps) declarations.insert(after_version, "#define SIM4CV_LAMPS\n");
  if (look & ChannelProgram::kShadows) declarations.insert(after_version, "#define SIM4CV_SHADOWS\n");
  if (look & ChannelProgram::kFull) declarations.insert(after_version, "#define SIM4CV_FULL_LOOK\n");
  if (look & ChannelProgram::kFlatGround) declarations.insert(after_version, "#define SIM4CV_FLAT_GROUND\n");
  if (look & ChannelProgram::kWet) declarations.insert(after_version, "#define SIM4CV_WET\n");
  if (look & ChannelProgram::kVariation) declarations.insert(after_version, "#define SIM4CV_VARIATION\n");
  std::string body = "void main() {\n";
  std::array<const char*, channels::kPixelChannelCount> declared{};  // functions shared by channels (shading.h) once
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    if ((planes & (1u << i)) == 0) continue;
    const ChannelOutput& output = *kChannelOutputs[i];
    const bool functions_new = std::find(declared.begin(), declared.end(), output.glsl_functions) == declared.end();
    if (output.glsl_functions != nullptr && functions_new) declarations += output.glsl_functions;
    declared[i] = output.glsl_functions;
    const std::string name = "out_" + std::string(channels::kPixelChannels[i].name);
    declarations += "layout(location = " + std::to_string(i) + ") out " + output.glsl_type + " " + name + ";\n";
    body += "#define OUT " + name + "\n  {" + output.glsl_body + "  }\n#undef OUT\n";
  }
  return declarations + body + "}\n";
}

}  // namespace

ChannelProgram::ChannelProgram(PlaneSet planes, uint32_t look) : planes_(planes) {
  const std::string fragment = FragmentShader(planes, look);
  program_ = LinkProgram(kVertexShader, fragment.c_str());
  const auto locate = [&](const char* name) { return glGetUniformLocation(program_, name); };
  u_model = locate("u_model");
  u_view = locate("u_view");
  u_projection = locate("u_projection");
  u_normal_matrix = locate("u_normal_matrix");
  u_instance = locate("u_instance");
  u_to_light = locate("u_to_light");
  u_previous_model = locate("u_previous_model");
  u_previous_view_projection = locate("u_previous_view_projection");
  u_viewport = locate("u_viewport");
  this->look.Locate(program_);
  u_lamps = locate("u_lamps");
  u_lamp_count = locate("u_lamp_count");
  u_headlights = locate("u_headlights");
  u_headlight_directions = locate("u_headlight_directions");
  u_headlight_count = locate("u_headlight_count");
}

ChannelProgram::~ChannelProgram() { glDeleteProgram(program_); }

}  // namespace sim4cv::render
