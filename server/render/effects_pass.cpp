#include "server/render/effects_pass.h"

#include <cmath>
#include <string>

#include "server/common/check.h"
#include "server/render/gl_program.h"
#include "server/render/projection.h"

namespace sim4cv::render {
namespace {

constexpr std::size_t kRgbPlane = *channels::IndexOf(proto::CHANNEL_RGB);
constexpr std::size_t kFlowPlane = *channels::IndexOf(proto::CHANNEL_FLOW);
constexpr uint32_t kPlaneSets = 1u << channels::kPixelChannelCount;
enum Variant : uint32_t { kLens = 1, kBlur = 2, kAntialias = 4 };
constexpr uint32_t kVariants = 8;
constexpr GLint kLensUnit = static_cast<GLint>(channels::kPixelChannelCount);  // texture units 0..n-1: the planes
constexpr std::size_t kLensesKept = 8;                                         // one per camera of a typical rig

uint32_t VariantOf(const CameraView& view) {
  const effects::CameraEffects& e = view.effects;
  return (effects::Distorts(e) ? kLens : 0u) | (e.motion_blur > 0 ? kBlur : 0u) | (e.antialias > 0 ? kAntialias : 0u);
}

// Linear RGB of a black body at `kelvin` relative to 6500 K, normalised to
// unit luminance (a fit of the Planckian locus in sRGB, good to a few per cent
// from 2000 to 12000 K): the light a camera balanced for `kelvin` treats as white.
Eigen::Vector3f WhiteOf(double kelvin) {
  const double t = kelvin / 100.0;
  double r = 0, g = 0, b = 0;
  if (t <= 66) {
    r = 255;
    g = 99.4708025861 * std::log(t) - 161.1195681661;
    b = t <= 19 ? 0 : 138.5177312231 * std::log(t - 10) - 305.0447927307;
  } else {
    r = 329.698727446 * std::pow(t - 60, -0.1332047592);
    g = 288.1221695283 * std::pow(t - 60, -0.0755148492);
    b = 255;
  }
  const auto linear = [](double c) { return std::pow(std::clamp(c, 1.0, 255.0) / 255.0, 2.2); };
  const Eigen::Vector3f white(static_cast<float>(linear(r)), static_cast<float>(linear(g)),
                              static_cast<float>(linear(b)));
  return white / (0.2126f * white.x() + 0.7152f * white.y() + 0.0722f * white.z());
}

constexpr const char* kVertexShader = R"(#version 330 core
void main() {
  gl_Position = vec4(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID & 2) * 2 - 1), 0.0, 1.0);
}
)";

// u_plane<i> samples scene plane i; out<i> writes plane i.
constexpr const char* kFunctions = R"(
uniform vec2 u_size;    // of the scene textures, texels
uniform vec2 u_extent;  // of this camera's image, pixels
uniform vec3 u_gain;    // exposure times white balance, on linear light
uniform float u_blur;   // shutter / frame period
uniform sampler2D u_lens_map;
uniform vec3 u_k;       // k1, k2, k3
uniform vec2 u_p;       // p1, p2
uniform vec2 u_focal;   // fx, fy of the distorted camera
uniform vec2 u_centre;  // cx, cy
uniform float u_widening;
uniform float u_truth_scale;  // ground-truth texels per image pixel

// Where a point of the widened pinhole render lands in the distorted image (lens.h).
vec2 DistortPixel(vec2 q) {
  vec2 n = (q - u_centre) * u_widening / u_focal;
  float r2 = dot(n, n);
  float radial = 1.0 + r2 * (u_k.x + r2 * (u_k.y + r2 * u_k.z));
  return u_centre + u_focal * (n * radial + vec2(2.0 * u_p.x * n.x * n.y + u_p.y * (r2 + 2.0 * n.x * n.x),
                                                 u_p.x * (r2 + 2.0 * n.y * n.y) + 2.0 * u_p.y * n.x * n.y));
}
#ifdef RGB_PLANE
vec3 Fetch(vec2 q) { return texture(RGB_PLANE, clamp(q, vec2(0.5), u_extent - 0.5) / u_size).rgb; }
float Luma(vec3 c) { return dot(c, vec3(0.299, 0.587, 0.114)); }
// FXAA (Lottes): blend across an edge found from the luma of the four
// diagonal neighbours; flat areas keep their pixel.
#ifdef LENS
vec3 Neighbour(vec2 q, vec2 offset) { return Fetch(q + offset); }
#else
// Without a lens q is a texel centre: exact texel reads, much cheaper than
// filtered ones on llvmpipe.
vec3 Neighbour(vec2 q, vec2 offset) {
  return texelFetch(RGB_PLANE, clamp(ivec2(q + offset), ivec2(0), ivec2(u_extent) - 1), 0).rgb;
}
#endif
vec3 Antialiased(vec2 q) {
  vec3 m = Neighbour(q, vec2(0.0));
  float nw = Luma(Neighbour(q, vec2(-1.0, -1.0))), ne = Luma(Neighbour(q, vec2(1.0, -1.0)));
  float sw = Luma(Neighbour(q, vec2(-1.0, 1.0))), se = Luma(Neighbour(q, vec2(1.0, 1.0)));
  float lm = Luma(m);
  float low = min(lm, min(min(nw, ne), min(sw, se))), high = max(lm, max(max(nw, ne), max(sw, se)));
  if (high - low < max(0.0312, high * 0.125)) return m;
  vec2 dir = vec2(-((nw + ne) - (sw + se)), (nw + sw) - (ne + se));
  float reduce = max((nw + ne + sw + se) * 0.03125, 1.0 / 128.0);
  dir = clamp(dir / (min(abs(dir.x), abs(dir.y)) + reduce), vec2(-8.0), vec2(8.0));
  vec3 a = 0.5 * (Fetch(q + dir * (1.0 / 3.0 - 0.5)) + Fetch(q + dir * (2.0 / 3.0 - 0.5)));
  vec3 b = 0.5 * a + 0.25 * (Fetch(q - 0.5 * dir) + Fetch(q + 0.5 * dir));
  float lb = Luma(b);
  return (lb < low || lb > high) ? a : b;
}
vec3 Rgb(vec2 q, ivec2 t) {
#ifdef ANTIALIAS
  vec3 c = Antialiased(q);
#else
  vec3 c = Neighbour(q, vec2(0.0));
#endif
#ifdef BLUR
  // The pixel's motion over the shutter, centred on the rendered instant, so
  // the boxes (of that instant) sit in the middle of the smear.
  vec2 f = texelFetch(FLOW_PLANE, t, 0).xy / u_truth_scale * u_blur;
  if (!any(isnan(f)) && dot(f, f) > 0.25) {
    vec3 sum = vec3(0.0);
    for (int i = 0; i < 8; ++i) sum += Fetch(q + f * (float(i) / 7.0 - 0.5));
    c = sum / 8.0;
  }
#endif
  // Gamma 2, as the look encodes (shading.h): squares and roots are far
  // cheaper than pow on llvmpipe. A gain of 1 gives back the same byte.
  return sqrt(min(c * c * u_gain, vec3(1.0)));
}
#endif
)";

// Components of a fragment output's GLSL type: vecN has N, a scalar 1.
std::size_t Components(const std::string& glsl_type) {
  return glsl_type.rfind("vec", 0) == 0 ? static_cast<std::size_t>(glsl_type[3] - '0') : 1;
}

// What of a texelFetch (always four components) an output of that type takes.
std::string Swizzle(const std::string& glsl_type) {
  const std::size_t n = Components(glsl_type);
  return n == 4 ? std::string() : std::string(".rgba").substr(0, n + 1);
}

// The channel's clear value (what it holds where nothing was drawn) as GLSL.
std::string ClearValue(const ChannelOutput& output) {
  std::string value = std::string(output.glsl_type) + "(";
  for (std::size_t c = 0; c < Components(output.glsl_type); ++c) {
    if (c > 0) value += ", ";
    if (output.integer) {
      value += std::to_string(output.clear_integer[c]) + "u";
    } else if (std::isinf(output.clear_float[c])) {
      value += "uintBitsToFloat(0x7f800000u)";
    } else {
      value += std::to_string(output.clear_float[c]);
    }
  }
  return value + ")";
}

std::string FragmentShader(PlaneSet through, PlaneSet inputs, uint32_t variant) {
  std::string defines = "#version 330 core\n";
  if (variant & kLens) defines += "#define LENS\n";
  if (variant & kBlur) defines += "#define BLUR\n";
  if (variant & kAntialias) defines += "#define ANTIALIAS\n";
  std::string declarations, body;
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    const PlaneSet bit = 1u << i;
    if (((through | inputs) & bit) == 0) continue;
    const ChannelOutput& output = *kChannelOutputs[i];
    const std::string sampler = "u_plane" + std::to_string(i), out = "out" + std::to_string(i);
    declarations += std::string("uniform ") + (output.integer ? "usampler2D " : "sampler2D ") + sampler + ";\n";
    if (i == kRgbPlane) defines += "#define RGB_PLANE " + sampler + "\n";
    if (i == kFlowPlane) defines += "#define FLOW_PLANE " + sampler + "\n";
    if ((through & bit) == 0) continue;
    declarations += "layout(location = " + std::to_string(i) + ") out " + output.glsl_type + " " + out + ";\n";
    const std::string fetched = "texelFetch(" + sampler + ", t, 0)" + Swizzle(output.glsl_type);
    // Past a lens's fold the image is black and holds nothing (lens.h).
    const std::string outside = (variant & kLens)
                                    ? "  if (!inside) " + out + " = " +
                                          (i == kRgbPlane ? "vec4(0.0, 0.0, 0.0, 1.0)" : ClearValue(output)) + ";\n"
                                    : "";
    if (i == kRgbPlane) {
      body += "  " + out + " = vec4(Rgb(q, t), 1.0);\n" + outside;
    } else if (i == kFlowPlane && (variant & kLens)) {
      // Flow says where the point was in the previous frame's render: map that place through the lens too.
      body += "  vec2 flow = " + fetched + " / u_truth_scale;\n  " + out +
              " = any(isnan(flow)) ? flow : p - DistortPixel(q - flow);\n" + outside;
    } else {
      body += "  " + out + " = " + fetched + ";\n" + outside;
    }
  }
  return defines + declarations + kFunctions + R"(
void main() {
  vec2 p = gl_FragCoord.xy;
#ifdef LENS
  vec2 q = texelFetch(u_lens_map, ivec2(p), 0).xy;
  bool inside = q.x >= 0.0;
  q = max(q, vec2(0.5));  // past the fold: any texel, overwritten below
#else
  vec2 q = p;
#endif
  ivec2 t = ivec2(q * u_truth_scale);  // the ground-truth texel under q
)" + body +
         "}\n";
}

}  // namespace

struct EffectsPass::Program {
  GLuint id = 0;
  GLint u_size = -1, u_extent = -1, u_gain = -1, u_blur = -1, u_k = -1, u_p = -1, u_focal = -1, u_centre = -1,
        u_widening = -1, u_truth_scale = -1;
  Program(PlaneSet through, uint32_t variant) {
    const PlaneSet inputs = (variant & kBlur) ? (1u << kFlowPlane) : 0u;
    id = LinkProgram(kVertexShader, FragmentShader(through, inputs, variant).c_str());
    glUseProgram(id);
    for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
      glUniform1i(glGetUniformLocation(id, ("u_plane" + std::to_string(i)).c_str()), static_cast<GLint>(i));
    }
    glUniform1i(glGetUniformLocation(id, "u_lens_map"), kLensUnit);
    // Unused uniforms are optimised out (-1), which glUniform* ignores.
    u_size = glGetUniformLocation(id, "u_size");
    u_extent = glGetUniformLocation(id, "u_extent");
    u_gain = glGetUniformLocation(id, "u_gain");
    u_blur = glGetUniformLocation(id, "u_blur");
    u_k = glGetUniformLocation(id, "u_k");
    u_p = glGetUniformLocation(id, "u_p");
    u_focal = glGetUniformLocation(id, "u_focal");
    u_centre = glGetUniformLocation(id, "u_centre");
    u_widening = glGetUniformLocation(id, "u_widening");
    u_truth_scale = glGetUniformLocation(id, "u_truth_scale");
  }
  ~Program() { glDeleteProgram(id); }
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;
};

EffectsPass::EffectsPass(uint32_t max_width, uint32_t max_height)
    : max_width_(max_width), max_height_(max_height), programs_(kPlaneSets * kVariants) {
  glGenFramebuffers(1, &framebuffer_);
}

EffectsPass::~EffectsPass() {
  for (const Lens& lens : lenses_) glDeleteTextures(1, &lens.texture);
  glDeleteRenderbuffers(static_cast<GLsizei>(targets_.size()), targets_.data());
  glDeleteFramebuffers(1, &framebuffer_);
}

PlaneSet EffectsPass::Through(const CameraView& view, PlaneSet planes) {
  if (effects::Distorts(view.effects)) return planes;
  return effects::NeedsPass(view.effects) ? planes & (1u << kRgbPlane) : 0u;
}

PlaneSet EffectsPass::Inputs(const CameraView& view, PlaneSet through) {
  return (through & (1u << kRgbPlane)) != 0 && view.effects.motion_blur > 0 ? 1u << kFlowPlane : 0u;
}

float EffectsPass::Prepare(const CameraView& view) {
  if (!effects::Distorts(view.effects)) return 1.0f;
  const auto same = [&](const Lens& lens) {
    return lens.key.width == view.width && lens.key.height == view.height && lens.key.fov_y_deg == view.fov_y_deg &&
           lens.key.effects.k1 == view.effects.k1 && lens.key.effects.k2 == view.effects.k2 &&
           lens.key.effects.k3 == view.effects.k3 && lens.key.effects.p1 == view.effects.p1 &&
           lens.key.effects.p2 == view.effects.p2;
  };
  for (current_ = 0; current_ < lenses_.size(); ++current_) {
    if (same(lenses_[current_])) return lenses_[current_].map.widening;
  }
  // A new lens or camera: its map is worked out once (milliseconds) and kept.
  if (lenses_.size() == kLensesKept) {
    glDeleteTextures(1, &lenses_.front().texture);
    lenses_.erase(lenses_.begin());
  }
  Lens lens{view, MakeLensMap(view), 0};
  glGenTextures(1, &lens.texture);
  glBindTexture(GL_TEXTURE_2D, lens.texture);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, static_cast<GLsizei>(view.width), static_cast<GLsizei>(view.height), 0,
               GL_RG, GL_FLOAT, lens.map.source.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  lens.map.source = {};  // on the GPU now
  lenses_.push_back(std::move(lens));
  current_ = lenses_.size() - 1;
  return lenses_.back().map.widening;
}

const EffectsPass::Program& EffectsPass::ProgramFor(PlaneSet through, uint32_t variant) {
  auto& cached = programs_[through + kPlaneSets * variant];
  if (!cached) cached = std::make_unique<Program>(through, variant);
  return *cached;
}

void EffectsPass::Draw(const CameraView& view, const Textures& scene, const Textures& truth, uint32_t truth_scale,
                       PlaneSet through) {
  const uint32_t variant = VariantOf(view);
  const Program& program = ProgramFor(through, variant);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  std::array<GLenum, channels::kPixelChannelCount> buffers{};
  const PlaneSet inputs = through | Inputs(view, through);
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    buffers[i] = GL_NONE;
    if ((inputs & (1u << i)) != 0) {
      glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(i));
      glBindTexture(GL_TEXTURE_2D, i == kRgbPlane ? scene[i] : truth[i]);
    }
    if ((through & (1u << i)) == 0) continue;
    if (targets_[i] == 0) {
      glGenRenderbuffers(1, &targets_[i]);
      glBindRenderbuffer(GL_RENDERBUFFER, targets_[i]);
      glRenderbufferStorage(GL_RENDERBUFFER, kChannelOutputs[i]->target_format, static_cast<GLsizei>(max_width_),
                            static_cast<GLsizei>(max_height_));
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i), GL_RENDERBUFFER,
                                targets_[i]);
    }
    buffers[i] = GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i);
  }
  glDrawBuffers(static_cast<GLsizei>(buffers.size()), buffers.data());
  SIM4CV_THROW_UNLESS(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                      "effects framebuffer is incomplete");
  if (variant & kLens) {
    glActiveTexture(GL_TEXTURE0 + static_cast<GLenum>(kLensUnit));
    glBindTexture(GL_TEXTURE_2D, lenses_[current_].texture);
  }
  glActiveTexture(GL_TEXTURE0);

  glUseProgram(program.id);
  const effects::CameraEffects& e = view.effects;
  const CameraIntrinsics k = IntrinsicsOf(view);
  const Eigen::Vector3f gain =
      static_cast<float>(std::exp2(e.exposure_ev)) * WhiteOf(6500.0).cwiseQuotient(WhiteOf(e.white_balance_k));
  glUniform2f(program.u_size, static_cast<float>(max_width_), static_cast<float>(max_height_));
  glUniform2f(program.u_extent, static_cast<float>(view.width), static_cast<float>(view.height));
  glUniform3fv(program.u_gain, 1, gain.data());
  glUniform1f(program.u_blur, static_cast<float>(e.motion_blur));
  glUniform3f(program.u_k, static_cast<float>(e.k1), static_cast<float>(e.k2), static_cast<float>(e.k3));
  glUniform2f(program.u_p, static_cast<float>(e.p1), static_cast<float>(e.p2));
  glUniform2f(program.u_focal, static_cast<float>(k.fx), static_cast<float>(k.fy));
  glUniform2f(program.u_centre, static_cast<float>(k.cx), static_cast<float>(k.cy));
  glUniform1f(program.u_widening, (variant & kLens) ? lenses_[current_].map.widening : 1.0f);
  glUniform1f(program.u_truth_scale, static_cast<float>(truth_scale));

  glDisable(GL_DEPTH_TEST);
  glDisable(GL_STENCIL_TEST);
  glDisable(GL_CULL_FACE);
  glDepthMask(GL_FALSE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glEnable(GL_CULL_FACE);
}

}  // namespace sim4cv::render
