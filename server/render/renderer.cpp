// One geometry pass writes every requested pixel channel through multiple
// render targets (one ChannelProgram per set of channels); a second,
// stencil-only pass counts each labelled instance's unoccluded silhouette
// with occlusion queries.
#include "server/render/renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <stdexcept>
#include <utility>

#include "server/common/check.h"
#include "server/render/camera_math.h"
#include "server/render/channel_program.h"
#include "server/render/effects_pass.h"
#include "server/render/gl_program.h"
#include "server/codec/jpeg.h"
#include "server/render/lens.h"
#include "server/render/render_targets.h"
#include "server/render/shadow_map.h"
#include "server/render/sky_pass.h"

namespace sim4cv::render {
namespace {

// Stencil references 1..255 tag successive instances, so the stencil buffer
// is cleared only once per 255 instances instead of once per instance.
constexpr GLint kMaxStencilReference = 255;

// The RGB channel's shadow map: 512 texels over 2x32 m of ground, 12.5 cm a texel.
constexpr GLsizei kShadowMapSize = 512;
constexpr float kShadowRadiusM = 32.0f;

// Flat ground (road, sidewalk, terrain, markings) receives shadows but casts
// none worth drawing: leaving it out of the shadow pass saves most of its fill.
bool FlatGround(uint32_t semantic) {
  using semantic::SemanticClass;
  for (SemanticClass ground : {SemanticClass::kRoad, SemanticClass::kSidewalk, SemanticClass::kTerrain,
                               SemanticClass::kLaneMarking, SemanticClass::kCrosswalk}) {
    if (semantic == static_cast<uint32_t>(ground)) return true;
  }
  return false;
}

constexpr std::size_t kRgbPlane = *channels::IndexOf(proto::CHANNEL_RGB);
constexpr std::size_t kMaskPlane = *channels::IndexOf(proto::CHANNEL_MASK);

// The planes drawn by the full look's programs when the look is full (ChannelOutput::reads_look).
PlaneSet LookPlanes() {
  PlaneSet planes = 0;
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    if (kChannelOutputs[i]->reads_look) planes |= 1u << i;
  }
  return planes;
}

struct MeshRange {
  GLsizei index_count = 0;
  size_t first_index = 0;
  Eigen::Vector3f sphere_center = Eigen::Vector3f::Zero();  // model frame
  float sphere_radius = 0.0f;
  bool flat_ground = false;  // every vertex is FlatGround: drawn last, casts no shadow
};

MeshRange BoundingSphere(const Mesh& mesh) {
  MeshRange range;
  if (mesh.vertices.empty()) return range;
  Eigen::Vector3f low = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f high = -low;
  for (const Vertex& vertex : mesh.vertices) {
    const Eigen::Vector3f p(vertex.position[0], vertex.position[1], vertex.position[2]);
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  range.sphere_center = 0.5f * (low + high);
  for (const Vertex& vertex : mesh.vertices) {
    const Eigen::Vector3f p(vertex.position[0], vertex.position[1], vertex.position[2]);
    range.sphere_radius = std::max(range.sphere_radius, (p - range.sphere_center).norm());
  }
  return range;
}

}  // namespace

struct Renderer::Impl {
  uint32_t max_width = 0;
  uint32_t max_height = 0;
  std::vector<MeshRange> meshes;
  const PlaneSet look_planes = LookPlanes();

  // Built the first time a set of channels is drawn in a look: index = plane
  // bits + kPlaneSets * RgbLook.
  static constexpr uint32_t kPlaneSets = 1u << channels::kPixelChannelCount;
  std::array<std::unique_ptr<ChannelProgram>, kPlaneSets * ChannelProgram::kRgbLooks> programs;
  const ChannelProgram* program = nullptr;  // of the frame being drawn
  GLuint vertex_array = 0, vertex_buffer = 0, index_buffer = 0;
  std::unique_ptr<RenderTargets> targets;  // at max_width x max_height
  // With a lens, the ground truth is drawn at twice the resolution (made the
  // first time): looked up through the lens map, its edges then move by at
  // most a quarter pixel instead of half a pixel.
  std::unique_ptr<RenderTargets> fine;
  std::vector<GLuint> queries;  // grows to the most instances seen in a frame

  Look look = LookOf(conditions::Conditions{});
  std::vector<Eigen::Vector3f> lamps;
  std::vector<Headlight> headlights;                    // this frame's cars
  std::vector<std::pair<float, uint32_t>> light_order;  // scratch: distance², index
  std::array<Eigen::Vector3f, kMaxLamps> nearest_lamps;
  std::array<Eigen::Vector3f, kMaxHeadlights> nearest_headlights, nearest_directions;
  // Orders light_order so that its first entries index the (at most `most`)
  // of `count` lights nearest `point`, `position(i)` being light i's; how many.
  template <typename Position>
  int Nearest(std::size_t count, Position position, const Eigen::Vector3f& point, int most);
  // Made the first time the full look draws RGB (with shadows, for the map).
  std::unique_ptr<ShadowMap> shadow_map;
  std::unique_ptr<SkyPass> sky;
  // Made the first time a camera has effects (effects_pass.h, jpeg.h).
  std::unique_ptr<EffectsPass> effects;
  std::unique_ptr<codec::JpegRoundTrip> jpeg;
  // Scratch for a lensed view's visibility: the undistorted mask and, per
  // instance, its pixels there and in the distorted mask.
  std::vector<uint16_t> scene_mask;
  std::vector<uint32_t> scene_visible, image_visible;

  // Per-frame scratch, kept to avoid allocating once warmed up.
  std::vector<uint32_t> labelled_drawn;  // indices of labelled items that survived culling
  Eigen::Vector3f lod_eye = Eigen::Vector3f::Zero();  // the current camera, for MeshFor
  float lod_focal_px = 1.0f;
  std::vector<InstanceId> queried_instances;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  // Here rather than in ~Renderer so a constructor that throws halfway still
  // frees what it made (deleting name 0 is a no-op).
  ~Impl() {
    glDeleteQueries(static_cast<GLsizei>(queries.size()), queries.data());
    glDeleteBuffers(1, &index_buffer);
    glDeleteBuffers(1, &vertex_buffer);
    glDeleteVertexArrays(1, &vertex_array);
  }

  void UploadMeshes(const std::vector<Mesh>& all_meshes);
  // Makes the program for `planes` and `look` current, drawing into `into`.
  void UsePlanes(RenderTargets& into, PlaneSet planes, uint32_t look);
  // One geometry pass of `items` into `into` at `scale` times the camera's
  // size, drawing `planes` with the RGB `look` (ChannelProgram::RgbLook).
  struct Pass {
    const CameraView& camera;
    Eigen::Matrix4f view, projection;  // projection: before the top-row-first mirror
    ShadowSampling shadow;
  };
  void DrawPass(const Pass& pass, std::span<const DrawItem> items, RenderTargets& into, uint32_t scale, PlaneSet planes,
                uint32_t look, std::span<uint32_t> unoccluded_pixels);
  // `item`'s bounding sphere in the world: centre, radius.
  std::pair<Eigen::Vector3f, float> WorldSphere(const DrawItem& item) const;
  bool InFrustum(const DrawItem& item, const std::array<Eigen::Vector4f, 6>& planes) const;
  // The mesh `item` is drawn with from the camera last set (DrawItem::far_mesh).
  void SetLodCamera(const CameraView& camera);
  MeshId MeshFor(const DrawItem& item) const;
  void Draw(const DrawItem& item) const;
  // The draw call of one mesh, with whatever program and uniforms are set.
  void DrawMesh(MeshId mesh) const;
  // Objects first, then flat ground after calling `before_ground`.
  void DrawScene(std::span<const DrawItem> items, const std::array<Eigen::Vector4f, 6>& planes,
                 std::span<uint32_t> unoccluded_pixels, const std::function<void()>& before_ground);
  // Draws the sun's shadow map of `items` for `camera`; how to sample it.
  // Only the moving casters whose shadow can fall inside `view_planes` (ShadowCanReach).
  ShadowSampling DrawShadows(const CameraView& camera, std::span<const DrawItem> items,
                             const std::array<Eigen::Vector4f, 6>& view_planes);
  // Reads the planes in `through` from the effects pass, the rest from the scene.
  void ReadBack(const CameraView& camera, const FrameBuffers& out, PlaneSet through) const;
  // With a lens, the occlusion queries counted undistorted pixels: rescales
  // them by each instance's visible pixels in the distorted and the
  // undistorted mask, so visibility means what it means without a lens.
  void RescaleUnoccluded(const CameraView& camera, const uint16_t* image_mask, std::span<uint32_t> unoccluded_pixels);
  void CountUnoccludedPixels(std::span<const DrawItem> items, std::span<uint32_t> unoccluded_pixels);
};

void Renderer::Impl::UploadMeshes(const std::vector<Mesh>& all_meshes) {
  std::vector<Vertex> vertices;
  std::vector<uint32_t> indices;
  for (const Mesh& mesh : all_meshes) {
    MeshRange range = BoundingSphere(mesh);
    range.flat_ground = std::all_of(mesh.vertices.begin(), mesh.vertices.end(),
                                    [](const Vertex& v) { return FlatGround(v.semantic & kSemanticBits); });
    range.first_index = indices.size();
    range.index_count = static_cast<GLsizei>(mesh.indices.size());
    const auto base_vertex = static_cast<uint32_t>(vertices.size());
    for (uint32_t index : mesh.indices) {
      SIM4CV_THROW_UNLESS(index < mesh.vertices.size(), "mesh " << meshes.size() << " has index " << index
                                                                << " past its " << mesh.vertices.size() << " vertices");
      indices.push_back(base_vertex + index);  // one shared buffer, so indices are rebased
    }
    vertices.insert(vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
    meshes.push_back(range);
  }
  glGenVertexArrays(1, &vertex_array);
  glBindVertexArray(vertex_array);
  glGenBuffers(1, &vertex_buffer);
  glBindBuffer(GL_ARRAY_BUFFER, vertex_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(Vertex)), vertices.data(),
               GL_STATIC_DRAW);
  glGenBuffers(1, &index_buffer);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer);  // recorded in the vertex array
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(uint32_t)), indices.data(),
               GL_STATIC_DRAW);
  const auto attribute = [](GLuint location, size_t offset) {
    glEnableVertexAttribArray(location);
    glVertexAttribPointer(location, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<const void*>(offset));
  };
  attribute(0, offsetof(Vertex, position));
  attribute(1, offsetof(Vertex, normal));
  attribute(2, offsetof(Vertex, color));
  glEnableVertexAttribArray(3);
  glVertexAttribIPointer(3, 1, GL_UNSIGNED_INT, sizeof(Vertex),
                         reinterpret_cast<const void*>(offsetof(Vertex, semantic)));
}

void Renderer::Impl::UsePlanes(RenderTargets& into, PlaneSet planes, uint32_t look) {
  into.Bind(planes);
  auto& cached = programs[planes + kPlaneSets * look];
  if (!cached) cached = std::make_unique<ChannelProgram>(planes, look);  // once per set of channels and look
  program = cached.get();
  glUseProgram(program->id());
}

std::pair<Eigen::Vector3f, float> Renderer::Impl::WorldSphere(const DrawItem& item) const {
  const MeshRange& mesh = meshes[item.mesh];
  const Eigen::Vector3f center =
      item.world_from_model.topLeftCorner<3, 3>() * mesh.sphere_center + item.world_from_model.block<3, 1>(0, 3);
  const float largest_scale = item.world_from_model.topLeftCorner<3, 3>().colwise().norm().maxCoeff();
  return {center, mesh.sphere_radius * largest_scale};
}

bool Renderer::Impl::InFrustum(const DrawItem& item, const std::array<Eigen::Vector4f, 6>& planes) const {
  const auto [center, radius] = WorldSphere(item);
  return std::all_of(planes.begin(), planes.end(),
                     [&](const Eigen::Vector4f& plane) { return plane.head<3>().dot(center) + plane.w() >= -radius; });
}

// Level of detail from the camera's own image, whatever a pass's scale or
// widened lens view, so every pass of a frame (shadows too) draws the same meshes.
void Renderer::Impl::SetLodCamera(const CameraView& camera) {
  lod_eye = camera.world_from_camera.block<3, 1>(0, 3);
  lod_focal_px = static_cast<float>(camera.height) / (2.0f * std::tan(camera.fov_y_deg * 3.14159265f / 360.0f));
}

MeshId Renderer::Impl::MeshFor(const DrawItem& item) const {
  if (item.far_mesh == kNoFarMesh) return item.mesh;
  const MeshRange& mesh = meshes[item.mesh];
  const Eigen::Vector3f centre =
      item.world_from_model.topLeftCorner<3, 3>() * mesh.sphere_center + item.world_from_model.block<3, 1>(0, 3);
  const float diameter_px = 2.0f * mesh.sphere_radius * lod_focal_px;
  return diameter_px < item.far_below_px * (centre - lod_eye).norm() ? item.far_mesh : item.mesh;
}

void Renderer::Impl::Draw(const DrawItem& item) const {
  const Eigen::Matrix3f normal_matrix = item.world_from_model.topLeftCorner<3, 3>().inverse().transpose();
  glUniformMatrix4fv(program->u_model, 1, GL_FALSE, item.world_from_model.data());
  glUniformMatrix4fv(program->u_previous_model, 1, GL_FALSE, item.previous_world_from_model.data());
  glUniformMatrix3fv(program->u_normal_matrix, 1, GL_FALSE, normal_matrix.data());
  glUniform1ui(program->u_instance, item.instance);
  DrawMesh(MeshFor(item));
}

void Renderer::Impl::DrawMesh(MeshId id) const {
  const MeshRange& mesh = meshes[id];
  glDrawElements(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT,
                 reinterpret_cast<const void*>(mesh.first_index * sizeof(uint32_t)));
}

void Renderer::Impl::DrawScene(std::span<const DrawItem> items, const std::array<Eigen::Vector4f, 6>& planes,
                               std::span<uint32_t> unoccluded_pixels, const std::function<void()>& before_ground) {
  // Write masks first: clears obey them, and the previous frame's counting pass turned them off.
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glStencilMask(0xFF);
  glDisable(GL_STENCIL_TEST);
  for (GLint i = 0; i < static_cast<GLint>(channels::kPixelChannelCount); ++i) {
    if ((program->planes() & (1u << i)) == 0) continue;
    const ChannelOutput& output = *kChannelOutputs[i];
    if (output.integer) {
      glClearBufferuiv(GL_COLOR, i, output.clear_integer.data());
    } else {
      glClearBufferfv(GL_COLOR, i, output.clear_float.data());
    }
  }
  glClearBufferfi(GL_DEPTH_STENCIL, 0, 1.0f, 0);

  labelled_drawn.clear();
  for (uint32_t i = 0; i < items.size(); ++i) {
    const DrawItem& item = items[i];
    SIM4CV_THROW_UNLESS(item.mesh < meshes.size(),
                        "draw item " << i << " names mesh " << item.mesh << " of " << meshes.size());
    SIM4CV_THROW_UNLESS(item.far_mesh == kNoFarMesh || item.far_mesh < meshes.size(),
                        "draw item " << i << " names far mesh " << item.far_mesh << " of " << meshes.size());
    SIM4CV_THROW_UNLESS(
        unoccluded_pixels.empty() || item.instance < unoccluded_pixels.size(),
        "instance " << item.instance << " does not fit unoccluded_pixels of size " << unoccluded_pixels.size());
  }
  // Objects first, flat ground last: the depth test then rejects the ground
  // under the objects before its fragments are shaded (llvmpipe tests depth
  // early), instead of shading those pixels twice.
  for (const bool ground_pass : {false, true}) {
    if (ground_pass) before_ground();
    for (uint32_t i = 0; i < items.size(); ++i) {
      const DrawItem& item = items[i];
      const MeshRange& mesh = meshes[item.mesh];
      if (mesh.flat_ground != ground_pass || mesh.index_count == 0 || !InFrustum(item, planes)) continue;
      Draw(item);
      if (item.instance != kUnlabelled) labelled_drawn.push_back(i);
    }
  }
}

void Renderer::Impl::DrawPass(const Pass& pass, std::span<const DrawItem> items, RenderTargets& into, uint32_t scale,
                              PlaneSet planes, uint32_t rgb_look, std::span<uint32_t> unoccluded_pixels) {
  const CameraView& camera = pass.camera;
  // GL's window origin is the bottom-left; mirroring y in clip space puts the
  // image's top row first in glReadPixels. The mirror also reverses winding.
  const Eigen::Matrix4f top_row_first = Eigen::Vector4f(1.0f, -1.0f, 1.0f, 1.0f).asDiagonal() * pass.projection;
  const Eigen::Matrix4f previous_view_projection = top_row_first * RigidInverse(camera.previous_world_from_camera);
  // The fast look keeps its fixed light; the full look's comes from the sun (look.h).
  const Eigen::Vector3f to_light = look.full ? look.to_sun : Eigen::Vector3f(-0.4f, 0.3f, 0.85f).normalized();
  const Eigen::Vector2f viewport(static_cast<float>(scale * camera.width), static_cast<float>(scale * camera.height));
  const Eigen::Vector3f camera_position = camera.world_from_camera.block<3, 1>(0, 3);
  const bool full_look = (rgb_look & ChannelProgram::kFull) != 0;
  SetLodCamera(camera);

  glViewport(0, 0, static_cast<GLsizei>(viewport.x()), static_cast<GLsizei>(viewport.y()));
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CW);
  int lamp_count = 0, headlight_count = 0;
  if ((rgb_look & ChannelProgram::kLamps) != 0) {
    const Eigen::Vector3f ahead = camera_position - 15.0f * camera.world_from_camera.block<3, 1>(0, 2);
    lamp_count = Nearest(
        lamps.size(), [&](uint32_t i) { return lamps[i]; }, ahead, kMaxLamps);
    for (int i = 0; i < lamp_count; ++i)
      nearest_lamps[static_cast<std::size_t>(i)] = lamps[light_order[static_cast<std::size_t>(i)].second];
    headlight_count = Nearest(
        headlights.size(), [&](uint32_t i) { return headlights[i].position; }, ahead, kMaxHeadlights);
    for (int i = 0; i < headlight_count; ++i) {
      const Headlight& car = headlights[light_order[static_cast<std::size_t>(i)].second];
      nearest_headlights[static_cast<std::size_t>(i)] = car.position;
      nearest_directions[static_cast<std::size_t>(i)] = car.direction;
    }
  }
  // The program of `program_look` made current with this pass's uniforms.
  const auto use = [&](uint32_t program_look) {
    UsePlanes(into, planes, program_look);
    glUniformMatrix4fv(program->u_view, 1, GL_FALSE, pass.view.data());
    glUniformMatrix4fv(program->u_projection, 1, GL_FALSE, top_row_first.data());
    glUniformMatrix4fv(program->u_previous_view_projection, 1, GL_FALSE, previous_view_projection.data());
    glUniform3fv(program->u_to_light, 1, to_light.data());
    glUniform2fv(program->u_viewport, 1, viewport.data());
    if (full_look) program->look.Apply(look, camera_position, pass.shadow, camera.noise_seed);
    if ((program_look & ChannelProgram::kLamps) != 0) {
      glUniform3fv(program->u_lamps, lamp_count, nearest_lamps[0].data());
      glUniform1i(program->u_lamp_count, lamp_count);
      glUniform3fv(program->u_headlights, headlight_count, nearest_headlights[0].data());
      glUniform3fv(program->u_headlight_directions, headlight_count, nearest_directions[0].data());
      glUniform1i(program->u_headlight_count, headlight_count);
    }
  };
  use(rgb_look);
  // The full look draws flat ground (last) with its own, shorter program.
  const auto before_ground = [&] {
    if (full_look) use(rgb_look | ChannelProgram::kFlatGround);
  };
  DrawScene(items, FrustumPlanes(pass.projection * pass.view), unoccluded_pixels, before_ground);
  if (full_look && (planes & (1u << kRgbPlane)) != 0) {
    if (!sky) sky = std::make_unique<SkyPass>();
    sky->Draw(static_cast<GLuint>(kRgbPlane), top_row_first * pass.view, camera_position, look, camera.noise_seed);
  }
}

template <typename Position>
int Renderer::Impl::Nearest(std::size_t count, Position position, const Eigen::Vector3f& point, int most) {
  light_order.clear();
  for (uint32_t i = 0; i < count; ++i) light_order.emplace_back((position(i) - point).squaredNorm(), i);
  const auto nearest = static_cast<int>(std::min<std::size_t>(light_order.size(), static_cast<std::size_t>(most)));
  std::partial_sort(light_order.begin(), light_order.begin() + nearest, light_order.end());
  return nearest;
}

ShadowSampling Renderer::Impl::DrawShadows(const CameraView& camera, std::span<const DrawItem> items,
                                           const std::array<Eigen::Vector4f, 6>& view_planes) {
  if (!shadow_map) shadow_map = std::make_unique<ShadowMap>(kShadowMapSize, kShadowRadiusM);
  const Eigen::Matrix4f clip_from_world = shadow_map->Fit(camera, look.to_sun);
  const auto planes = FrustumPlanes(clip_from_world);
  const GLint u_model = shadow_map->ModelLocation();
  SetLodCamera(camera);
  // Fixed casters only when the map moved or the sun turned; moving ones every frame.
  const auto draw_casters = [&](bool fixed) {
    for (const DrawItem& item : items) {
      if (item.fixed != fixed || item.mesh >= meshes.size() || meshes[item.mesh].flat_ground ||
          !InFrustum(item, planes)) {
        continue;
      }
      // The fixed casters' depth is kept for other views; a moving caster is drawn for this one only.
      if (!fixed) {
        const auto [centre, radius] = WorldSphere(item);
        if (!ShadowCanReach(centre, radius, look.to_sun, view_planes)) continue;
      }
      glUniformMatrix4fv(u_model, 1, GL_FALSE, item.world_from_model.data());
      DrawMesh(MeshFor(item));
    }
  };
  if (!shadow_map->FixedCastersCached(clip_from_world)) {
    shadow_map->BeginFixed(clip_from_world);
    draw_casters(true);
  }
  shadow_map->BeginMoving(clip_from_world);
  draw_casters(false);
  return shadow_map->End(clip_from_world);
}

void Renderer::Impl::ReadBack(const CameraView& camera, const FrameBuffers& out, PlaneSet through) const {
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  for (GLuint i = 0; i < channels::kPixelChannelCount; ++i) {
    if (out[i] == nullptr) continue;
    glBindFramebuffer(GL_READ_FRAMEBUFFER,
                      (through & (1u << i)) != 0 ? effects->framebuffer() : targets->framebuffer());
    glReadBuffer(GL_COLOR_ATTACHMENT0 + i);
    glReadPixels(0, 0, static_cast<GLsizei>(camera.width), static_cast<GLsizei>(camera.height),
                 kChannelOutputs[i]->read_format, kChannelOutputs[i]->read_type, out[i]);
  }
}

void Renderer::Impl::RescaleUnoccluded(const CameraView& camera, const uint16_t* image_mask,
                                       std::span<uint32_t> unoccluded_pixels) {
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  scene_mask.resize(static_cast<std::size_t>(max_width) * max_height);  // once: the largest image
  scene_visible.assign(unoccluded_pixels.size(), 0);                    // no reallocation once warmed up
  image_visible.assign(unoccluded_pixels.size(), 0);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, targets->framebuffer());
  glReadBuffer(GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(kMaskPlane));
  glReadPixels(0, 0, static_cast<GLsizei>(camera.width), static_cast<GLsizei>(camera.height), GL_RED_INTEGER,
               GL_UNSIGNED_SHORT, scene_mask.data());
  for (std::size_t i = 0; i < pixels; ++i) {
    if (scene_mask[i] < scene_visible.size()) ++scene_visible[scene_mask[i]];
    if (image_mask[i] < image_visible.size()) ++image_visible[image_mask[i]];
  }
  for (std::size_t id = 1; id < unoccluded_pixels.size(); ++id) {
    if (scene_visible[id] == 0 || image_visible[id] == 0) continue;
    unoccluded_pixels[id] = static_cast<uint32_t>(
        std::lround(static_cast<double>(unoccluded_pixels[id]) * image_visible[id] / scene_visible[id]));
  }
}

// Each instance is drawn alone with the depth test off; the stencil lets a
// pixel pass only the first time this instance covers it, so overlapping
// triangles (and several items sharing the id) count once.
void Renderer::Impl::CountUnoccludedPixels(std::span<const DrawItem> items, std::span<uint32_t> unoccluded_pixels) {
  std::sort(labelled_drawn.begin(), labelled_drawn.end(), [&](uint32_t a, uint32_t b) {
    return items[a].instance != items[b].instance ? items[a].instance < items[b].instance : a < b;
  });
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glEnable(GL_STENCIL_TEST);
  glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);

  queried_instances.clear();
  GLint reference = 0;  // the stencil holds 0 after DrawScene's clear
  for (size_t first = 0; first < labelled_drawn.size();) {
    const InstanceId instance = items[labelled_drawn[first]].instance;
    if (reference == kMaxStencilReference) {
      glClear(GL_STENCIL_BUFFER_BIT);
      reference = 0;
    }
    ++reference;
    glStencilFunc(GL_NOTEQUAL, reference, 0xFF);
    if (queries.size() <= queried_instances.size()) {
      queries.push_back(0);
      glGenQueries(1, &queries.back());
    }
    glBeginQuery(GL_SAMPLES_PASSED, queries[queried_instances.size()]);
    for (; first < labelled_drawn.size() && items[labelled_drawn[first]].instance == instance; ++first) {
      Draw(items[labelled_drawn[first]]);
    }
    glEndQuery(GL_SAMPLES_PASSED);
    queried_instances.push_back(instance);
  }
  for (size_t i = 0; i < queried_instances.size(); ++i) {
    GLuint samples = 0;
    glGetQueryObjectuiv(queries[i], GL_QUERY_RESULT, &samples);
    unoccluded_pixels[queried_instances[i]] = samples;
  }
}

Renderer::Renderer(const std::vector<Mesh>& meshes, uint32_t max_width, uint32_t max_height)
    : impl_(std::make_unique<Impl>()) {
  SIM4CV_THROW_UNLESS(max_width > 0 && max_height > 0, "render size " << max_width << "x" << max_height);
  Impl& gl = *impl_;
  gl.max_width = max_width;
  gl.max_height = max_height;
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    SIM4CV_DEMAND(kChannelOutputs[i]->channel == channels::kPixelChannels[i].id);
  }
  gl.UploadMeshes(meshes);
  gl.targets = std::make_unique<RenderTargets>(max_width, max_height);
  ThrowOnGlError("Renderer setup");
}

Renderer::~Renderer() = default;

void Renderer::SetLook(const Look& look) { impl_->look = look; }

void Renderer::SetLamps(std::vector<Eigen::Vector3f> lamps) {
  impl_->lamps = std::move(lamps);
  impl_->light_order.reserve(impl_->lamps.size());  // no allocation per frame
}

void Renderer::SetHeadlights(std::span<const Headlight> headlights) {
  impl_->headlights.assign(headlights.begin(), headlights.end());
  impl_->light_order.reserve(headlights.size());  // only grows: no allocation once the cars stop growing
}

void Renderer::Render(const CameraView& camera, std::span<const DrawItem> items, const FrameBuffers& out,
                      std::span<uint32_t> unoccluded_pixels) {
  Impl& gl = *impl_;
  SIM4CV_THROW_UNLESS(
      camera.width > 0 && camera.height > 0 && camera.width <= gl.max_width && camera.height <= gl.max_height,
      "camera size " << camera.width << "x" << camera.height << " outside 1x1.." << gl.max_width << "x"
                     << gl.max_height);
  PlaneSet wanted = 0;
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    if (out[i] != nullptr) wanted |= 1u << i;
  }
  if (wanted == 0) return;  // nothing asked for: nothing drawn
  // Camera effects: a lens widens the pinhole view the scene is drawn with
  // (the pass then distorts it); motion blur needs the flow; a lensed view's
  // visibility needs the undistorted mask.
  const PlaneSet through = EffectsPass::Through(camera, wanted);
  const bool lens = effects::Distorts(camera.effects);
  const bool rescale = lens && !unoccluded_pixels.empty() && out[kMaskPlane] != nullptr;
  // With a lens every channel but RGB comes from the fine targets, the flow
  // for motion blur too; the scene's targets then draw RGB, and the mask
  // when visibility needs it.
  const PlaneSet inputs = EffectsPass::Inputs(camera, through);
  const PlaneSet fine_planes = lens ? (wanted | inputs) & ~(1u << kRgbPlane) : 0u;
  const PlaneSet planes = ((wanted | inputs) & ~fine_planes) | (rescale ? 1u << kMaskPlane : 0u);
  if (through != 0 && !gl.effects) gl.effects = std::make_unique<EffectsPass>(gl.max_width, gl.max_height);
  const float widening = lens ? gl.effects->Prepare(camera) : 1.0f;
  // The light (shadows, noise, lamps) is RGB's alone; the full look's materials are every look plane's.
  const bool full_rgb = gl.look.full && (planes & (1u << kRgbPlane)) != 0;
  const auto full_look = [&](PlaneSet drawn) { return gl.look.full && (drawn & gl.look_planes) != 0; };
  // The materials (RGB's and albedo's): the full look's, wet or dry, with or without the
  // colour jitter, or the fast one.
  const auto material_look = [&](PlaneSet drawn) {
    if (!full_look(drawn)) return static_cast<uint32_t>(ChannelProgram::kFast);
    return ChannelProgram::kFull | (gl.look.wetness > 0.0f ? ChannelProgram::kWet : 0u) |
           (gl.look.variation != 0 ? ChannelProgram::kVariation : 0u);
  };
  glBindVertexArray(gl.vertex_array);
  Impl::Pass pass{
      camera, RigidInverse(camera.world_from_camera),
      Perspective(lens ? WidenedFov(camera.fov_y_deg, widening) : camera.fov_y_deg,
                  static_cast<float>(camera.width) / static_cast<float>(camera.height), camera.near_m, camera.far_m),
      {}};
  if (full_rgb && gl.look.shadows) {
    pass.shadow = gl.DrawShadows(camera, items, FrustumPlanes(pass.projection * pass.view));
  }
  uint32_t rgb_look = material_look(planes);
  if (full_rgb) {
    rgb_look |= (pass.shadow.texture != 0 ? ChannelProgram::kShadows : 0u) |
                (gl.look.noise_read > 0.0f || gl.look.noise_shot > 0.0f ? ChannelProgram::kNoise : 0u) |
                (gl.look.lights > 0.0f && !(gl.lamps.empty() && gl.headlights.empty()) ? ChannelProgram::kLamps : 0u);
  }
  constexpr uint32_t kFineScale = 2;
  if (fine_planes != 0) {
    if (!gl.fine) gl.fine = std::make_unique<RenderTargets>(kFineScale * gl.max_width, kFineScale * gl.max_height);
    gl.DrawPass(pass, items, *gl.fine, kFineScale, fine_planes,
                material_look(fine_planes), {});
  }
  // Last, so the counting pass below finds this pass's stencil, program and viewport.
  if (planes != 0) {
    gl.DrawPass(pass, items, *gl.targets, 1, planes, rgb_look, unoccluded_pixels);
  }
  if (through != 0) {
    gl.effects->Draw(camera, gl.targets->textures(), lens ? gl.fine->textures() : gl.targets->textures(),
                     lens ? kFineScale : 1, through);
  }
  gl.ReadBack(camera, out, through);
  if (camera.effects.jpeg_quality > 0 && out[kRgbPlane] != nullptr) {
    if (!gl.jpeg) gl.jpeg = std::make_unique<codec::JpegRoundTrip>();
    gl.jpeg->Apply(out[kRgbPlane], camera.width, camera.height, static_cast<int>(camera.effects.jpeg_quality));
  }
  if (!unoccluded_pixels.empty() && planes != 0) {
    glBindFramebuffer(GL_FRAMEBUFFER, gl.targets->framebuffer());
    glUseProgram(gl.program->id());  // the scene pass's, whose uniforms hold this view
    gl.CountUnoccludedPixels(items, unoccluded_pixels);
    if (rescale) {
      gl.RescaleUnoccluded(camera, reinterpret_cast<const uint16_t*>(out[kMaskPlane]), unoccluded_pixels);
    }
  }
  ThrowOnGlError("Renderer::Render");
}

}  // namespace sim4cv::render
