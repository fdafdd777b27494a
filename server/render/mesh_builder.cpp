#include "server/render/mesh_builder.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <utility>

#include "protocol/semantic_classes.h"
#include "server/common/check.h"

namespace sim4cv::render {
namespace {

// Corners counter-clockwise seen from the side `normal` points to.
void AddQuad(Mesh& mesh, const std::array<Eigen::Vector3f, 4>& corners, const Eigen::Vector3f& normal,
             const Eigen::Vector3f& color) {
  const auto first = static_cast<uint32_t>(mesh.vertices.size());
  for (const Eigen::Vector3f& corner : corners) {
    mesh.vertices.push_back({{corner.x(), corner.y(), corner.z()},
                             {normal.x(), normal.y(), normal.z()},
                             {color.x(), color.y(), color.z()},
                             mesh.semantic});
  }
  for (uint32_t corner : {0u, 1u, 2u, 0u, 2u, 3u}) mesh.indices.push_back(first + corner);
}

void AppendBox(Mesh& mesh, const Eigen::Vector3f& center, const Eigen::Vector3f& half_extents,
               const Eigen::Vector3f& color) {
  for (int axis = 0; axis < 3; ++axis) {
    // u x v = axis, so (u, v) corners in this order are counter-clockwise seen from +axis.
    const Eigen::Vector3f u = Eigen::Vector3f::Unit((axis + 1) % 3) * half_extents[(axis + 1) % 3];
    const Eigen::Vector3f v = Eigen::Vector3f::Unit((axis + 2) % 3) * half_extents[(axis + 2) % 3];
    for (float side : {1.0f, -1.0f}) {
      const Eigen::Vector3f normal = side * Eigen::Vector3f::Unit(axis);
      const Eigen::Vector3f face_center = center + normal * half_extents[axis];
      std::array<Eigen::Vector3f, 4> corners = {face_center - u - v, face_center + u - v, face_center + u + v,
                                                face_center - u + v};
      if (side < 0.0f) std::reverse(corners.begin(), corners.end());
      AddQuad(mesh, corners, normal, color);
    }
  }
}

Eigen::Vector2f LeftOf(const Eigen::Vector2f& direction) { return {-direction.y(), direction.x()}; }

// Offset directions at each polyline vertex, scaled (mitred) so strips keep
// their width through the corners.
std::vector<Eigen::Vector2f> MiterOffsets(const std::vector<Eigen::Vector2f>& loop) {
  const size_t n = loop.size();
  std::vector<Eigen::Vector2f> offsets(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2f left_in = LeftOf((loop[i] - loop[(i + n - 1) % n]).normalized());
    const Eigen::Vector2f left_out = LeftOf((loop[(i + 1) % n] - loop[i]).normalized());
    const Eigen::Vector2f miter = (left_in + left_out).normalized();
    // Hairpin corners would make the miter spike to infinity; cap it.
    offsets[i] = miter / std::max(miter.dot(left_out), 0.25f);
  }
  return offsets;
}

// A closed ribbon between lateral offsets right < left (metres, + is left of travel).
void AppendRibbon(Mesh& mesh, const std::vector<Eigen::Vector2f>& loop, const std::vector<Eigen::Vector2f>& offsets,
                  float right, float left, float z, const Eigen::Vector3f& color) {
  const auto at = [&](size_t i, float lateral) {
    const Eigen::Vector2f p = loop[i] + lateral * offsets[i];
    return Eigen::Vector3f(p.x(), p.y(), z);
  };
  for (size_t i = 0; i < loop.size(); ++i) {
    const size_t next = (i + 1) % loop.size();
    AddQuad(mesh, {at(i, right), at(next, right), at(next, left), at(i, left)}, Eigen::Vector3f::UnitZ(), color);
  }
}

void AppendDashedLine(Mesh& mesh, const std::vector<Eigen::Vector2f>& loop, float half_width, float dash_m,
                      float period_m, float z, const Eigen::Vector3f& color) {
  float segment_start_s = 0.0f;  // arc length where the segment starts, so the pattern runs on across corners
  for (size_t i = 0; i < loop.size(); ++i) {
    const Eigen::Vector2f a = loop[i];
    const Eigen::Vector2f b = loop[(i + 1) % loop.size()];
    const float length = (b - a).norm();
    const Eigen::Vector2f direction = (b - a) / length;
    const Eigen::Vector2f side = LeftOf(direction) * half_width;
    for (float dash_s = std::floor(segment_start_s / period_m) * period_m; dash_s < segment_start_s + length;
         dash_s += period_m) {
      const float from = std::max(dash_s, segment_start_s) - segment_start_s;
      const float to = std::min(dash_s + dash_m, segment_start_s + length) - segment_start_s;
      if (to <= from) continue;
      const auto corner = [&](float s, float lateral) {
        const Eigen::Vector2f p = a + s * direction + lateral * side;
        return Eigen::Vector3f(p.x(), p.y(), z);
      };
      AddQuad(mesh, {corner(from, -1.0f), corner(to, -1.0f), corner(to, 1.0f), corner(from, 1.0f)},
              Eigen::Vector3f::UnitZ(), color);
    }
    segment_start_s += length;
  }
}

}  // namespace

Mesh MakeBox(const Eigen::Vector3f& half_extents, const Eigen::Vector3f& color) {
  SIM4CV_THROW_UNLESS((half_extents.array() > 0.0f).all(), "box half extents must be > 0");
  Mesh mesh;
  AppendBox(mesh, Eigen::Vector3f::Zero(), half_extents, color);
  return mesh;
}

Mesh MakeGroundPlane(float half_size, const Eigen::Vector3f& color) {
  SIM4CV_THROW_UNLESS(half_size > 0.0f, "ground half size " << half_size << " must be > 0");
  constexpr int kCells = 8;
  constexpr float kTintContrast = 0.06f;
  const float cell = 2.0f * half_size / kCells;
  Mesh mesh;
  for (int row = 0; row < kCells; ++row) {
    for (int column = 0; column < kCells; ++column) {
      const float x0 = -half_size + column * cell;
      const float y0 = -half_size + row * cell;
      const float tint = ((row + column) % 2 == 0) ? 1.0f + kTintContrast : 1.0f - kTintContrast;
      AddQuad(mesh,
              {Eigen::Vector3f(x0, y0, 0.0f), Eigen::Vector3f(x0 + cell, y0, 0.0f),
               Eigen::Vector3f(x0 + cell, y0 + cell, 0.0f), Eigen::Vector3f(x0, y0 + cell, 0.0f)},
              Eigen::Vector3f::UnitZ(), (color * tint).cwiseMin(1.0f));
    }
  }
  return Labelled(std::move(mesh), SemanticClass::kTerrain);
}

Mesh MakeRoadLoop(const std::vector<Eigen::Vector2f>& closed_centerline, float lane_width,
                  const Eigen::Vector3f& asphalt, const Eigen::Vector3f& marking) {
  SIM4CV_THROW_UNLESS(lane_width > 0.5f, "lane width " << lane_width << " must be > 0.5 m");
  std::vector<Eigen::Vector2f> loop = closed_centerline;
  if (loop.size() > 1 && loop.front() == loop.back()) loop.pop_back();  // accept an explicitly closed polyline too
  SIM4CV_THROW_UNLESS(loop.size() >= 3, "a road loop needs at least 3 distinct points");
  for (size_t i = 0; i < loop.size(); ++i) {
    SIM4CV_THROW_UNLESS((loop[(i + 1) % loop.size()] - loop[i]).norm() > 1e-3f,
                        "road centerline point " << i << " repeats its predecessor");
  }
  // Heights above the ground and between asphalt and paint: enough to avoid
  // z-fighting at a few hundred metres with a 24-bit depth buffer.
  constexpr float kAsphaltZ = 0.02f;
  constexpr float kMarkingZ = 0.04f;
  constexpr float kLineWidth = 0.15f;
  constexpr float kEdgeInset = 0.10f;
  constexpr float kDashLength = 3.0f;
  constexpr float kDashPeriod = 9.0f;
  const std::vector<Eigen::Vector2f> offsets = MiterOffsets(loop);
  Mesh mesh;
  mesh.semantic = static_cast<uint32_t>(SemanticClass::kRoad);
  AppendRibbon(mesh, loop, offsets, -lane_width, lane_width, kAsphaltZ, asphalt);
  mesh.semantic = static_cast<uint32_t>(SemanticClass::kLaneMarking);
  const float edge_outer = lane_width - kEdgeInset;
  const float edge_inner = edge_outer - kLineWidth;
  AppendRibbon(mesh, loop, offsets, edge_inner, edge_outer, kMarkingZ, marking);
  AppendRibbon(mesh, loop, offsets, -edge_outer, -edge_inner, kMarkingZ, marking);
  AppendDashedLine(mesh, loop, 0.5f * kLineWidth, kDashLength, kDashPeriod, kMarkingZ, marking);
  return mesh;
}

namespace {

// A style's silhouette as fractions of the car's length (x, from the rear
// -0.5 to the front 0.5) and height (from the ground 0 to the roof 1).
struct CarProfile {
  float shoulder;                 // top of the painted body
  float cabin_rear, cabin_front;  // the glasshouse
};

CarProfile ProfileOf(CarStyle style) {
  switch (style) {
    case CarStyle::kSedan: return {0.55f, -0.28f, 0.18f};
    case CarStyle::kHatchback: return {0.55f, -0.46f, 0.15f};
    case CarStyle::kEstate: return {0.55f, -0.48f, 0.18f};
    case CarStyle::kSuv: return {0.62f, -0.46f, 0.22f};
    case CarStyle::kVan: return {0.6f, -0.49f, 0.36f};
    case CarStyle::kPickup: return {0.6f, -0.08f, 0.22f};
    case CarStyle::kTruck: return {0.55f, 0.2f, 0.46f};
  }
  return {0.55f, -0.46f, 0.15f};
}

}  // namespace

Mesh MakeCarMesh(float length, float width, float height, const Eigen::Vector3f& color, CarStyle style) {
  SIM4CV_THROW_UNLESS(length > 0.0f && width > 0.0f && height > 0.0f, "car dimensions must be > 0");
  const Eigen::Vector3f tyre_color(0.04f, 0.04f, 0.045f);
  const Eigen::Vector3f glass(0.05f, 0.06f, 0.07f);
  const Eigen::Vector3f headlight(0.9f, 0.9f, 0.82f), taillight(0.55f, 0.03f, 0.03f);
  const CarProfile profile = ProfileOf(style);
  const float bottom = -0.5f * height;
  const auto at = [&](float fraction) { return bottom + fraction * height; };
  const float wheel_top = at(style == CarStyle::kSuv || style == CarStyle::kPickup ? 0.4f : 0.35f);
  const float body_bottom = at(0.15f);
  const float shoulder = at(profile.shoulder);
  const Eigen::Vector3f wheel_half(0.1f * length, 0.09f * width, 0.5f * (wheel_top - bottom));
  Mesh mesh;
  for (float x : {-0.32f * length, 0.32f * length}) {
    // Inset a little so the tyre sides are not coplanar with the body sides (z-fighting).
    const float wheel_y = 0.5f * width - wheel_half.y() - 0.02f * width;
    for (float y : {-wheel_y, wheel_y}) {
      AppendBox(mesh, {x, y, bottom + wheel_half.z()}, wheel_half, tyre_color);
    }
  }
  // The body, 1 % of the length short of each end where the lamps stand
  // proud to the exact bounds (no coplanar faces to z-fight).
  const Eigen::Vector3f lamp_half(0.01f * length, 0.1f * width, 0.05f * height);
  AppendBox(mesh, {0.0f, 0.0f, 0.5f * (body_bottom + shoulder)},
            {0.5f * length - 2.0f * lamp_half.x(), 0.5f * width, 0.5f * (shoulder - body_bottom)}, color);
  // The glasshouse and its painted roof, which reaches the top of the bounds.
  const float rear = profile.cabin_rear * length, front = profile.cabin_front * length;
  const float roof_bottom = at(0.93f);
  AppendBox(mesh, {0.5f * (rear + front), 0.0f, 0.5f * (shoulder + roof_bottom)},
            {0.5f * (front - rear), 0.43f * width, 0.5f * (roof_bottom - shoulder)}, glass);
  AppendBox(mesh, {0.5f * (rear + front), 0.0f, 0.5f * (roof_bottom + at(1.0f))},
            {0.5f * (front - rear) - 0.01f * length, 0.45f * width, 0.5f * (at(1.0f) - roof_bottom)}, color);
  if (style == CarStyle::kTruck) {  // the cargo box behind the cab, up to the top of the bounds
    const float box_rear = -0.5f * length + 2.0f * lamp_half.x(), box_front = rear - 0.02f * length;
    AppendBox(mesh, {0.5f * (box_rear + box_front), 0.0f, 0.5f * (shoulder + at(1.0f))},
              {0.5f * (box_front - box_rear), 0.5f * width, 0.5f * (at(1.0f) - shoulder)}, {0.86f, 0.86f, 0.84f});
  }
  const float lamp_z = at(profile.shoulder - 0.12f);
  const std::size_t first_lamp = mesh.vertices.size();
  for (float y : {-0.33f * width, 0.33f * width}) {
    AppendBox(mesh, {0.5f * length - lamp_half.x(), y, lamp_z}, lamp_half, headlight);
    AppendBox(mesh, {-0.5f * length + lamp_half.x(), y, lamp_z}, lamp_half, taillight);
  }
  MarkEmissive(mesh, first_lamp);  // lit at night
  return Labelled(std::move(mesh), SemanticClass::kCar);
}

UavParts MakeUavParts(float span, const Eigen::Vector3f& color) {
  SIM4CV_THROW_UNLESS(span > 0.0f, "UAV span " << span << " must be > 0");
  const Eigen::Vector3f motor_color(0.1f, 0.1f, 0.1f), blade_color(0.2f, 0.2f, 0.22f);
  const float arm_thickness = 0.04f * span;
  const Mesh arm = MakeBox({0.5f * span, 0.5f * arm_thickness, 0.5f * arm_thickness}, color);
  UavParts parts;
  AppendBox(parts.body, Eigen::Vector3f::Zero(), Eigen::Vector3f(0.12f, 0.12f, 0.05f) * span, color);
  for (float yaw_deg : {45.0f, -45.0f}) {
    Eigen::Matrix4f transform = Eigen::Matrix4f::Identity();
    transform.topLeftCorner<3, 3>() = Eigen::AngleAxisf(yaw_deg * std::numbers::pi_v<float> / 180.0f, Eigen::Vector3f::UnitZ())
                                          .toRotationMatrix();
    AppendMesh(parts.body, arm, transform);
  }
  const Eigen::Vector3f motor_half(0.03f * span, 0.03f * span, 0.02f * span);
  for (const Eigen::Vector3f& hub : RotorHubs(span)) {
    AppendBox(parts.body, hub - Eigen::Vector3f(0, 0, motor_half.z()), motor_half, motor_color);  // on the arm tip
  }
  // Two blades crossing at the hub, 0.12 span long each way: any turn stays
  // inside the span.
  const float blade = 0.12f * span;
  AppendBox(parts.rotor, {0.0f, 0.0f, 0.005f * span}, {blade, 0.015f * span, 0.005f * span}, blade_color);
  AppendBox(parts.rotor, {0.0f, 0.0f, 0.005f * span}, {0.015f * span, blade, 0.0049f * span}, blade_color);
  parts.body = Labelled(std::move(parts.body), SemanticClass::kUav);
  parts.rotor = Labelled(std::move(parts.rotor), SemanticClass::kUav);
  return parts;
}

std::array<Eigen::Vector3f, 4> RotorHubs(float span) {
  const float tip = 0.5f * span / std::sqrt(2.0f);
  const float top = 0.02f * span + 0.04f * span;  // arm top plus the motor's height
  return {Eigen::Vector3f(tip, tip, top), Eigen::Vector3f(-tip, -tip, top), Eigen::Vector3f(tip, -tip, top),
          Eigen::Vector3f(-tip, tip, top)};
}

Eigen::Matrix4f RotorPose(float span, std::size_t rotor, double sim_time) {
  // About 25 revolutions a second, diagonal pairs turning opposite ways as on a real quadrotor.
  const double turns = 25.0 * sim_time;
  const double angle = 2.0 * std::numbers::pi * (turns - std::floor(turns)) * (rotor < 2 ? 1.0 : -1.0);
  Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
  pose.topLeftCorner<3, 3>() = Eigen::AngleAxisf(static_cast<float>(angle), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  pose.block<3, 1>(0, 3) = RotorHubs(span)[rotor];
  return pose;
}

Mesh MakeUavMesh(float span, const Eigen::Vector3f& color) {
  const UavParts parts = MakeUavParts(span, color);
  Mesh mesh = parts.body;
  for (std::size_t rotor = 0; rotor < 4; ++rotor) AppendMesh(mesh, parts.rotor, RotorPose(span, rotor, 0.0));
  return mesh;
}

void AppendMesh(Mesh& into, const Mesh& part, const Eigen::Matrix4f& transform) {
  const Eigen::Matrix3f linear = transform.topLeftCorner<3, 3>();
  const Eigen::Matrix3f normal_matrix = linear.inverse().transpose();
  const bool mirrors = linear.determinant() < 0.0f;
  const auto first = static_cast<uint32_t>(into.vertices.size());
  for (const Vertex& vertex : part.vertices) {
    const Eigen::Vector3f position =
        linear * Eigen::Vector3f(vertex.position[0], vertex.position[1], vertex.position[2]) +
        transform.block<3, 1>(0, 3);
    const Eigen::Vector3f normal =
        (normal_matrix * Eigen::Vector3f(vertex.normal[0], vertex.normal[1], vertex.normal[2])).normalized();
    // An unlabelled part takes the class of what it is appended to.
    into.vertices.push_back({{position.x(), position.y(), position.z()},
                             {normal.x(), normal.y(), normal.z()},
                             {vertex.color[0], vertex.color[1], vertex.color[2]},
                             (vertex.semantic & kSemanticBits) == 255
                                 ? (vertex.semantic & ~kSemanticBits) | into.semantic
                                 : vertex.semantic});
  }
  for (size_t i = 0; i + 2 < part.indices.size(); i += 3) {
    into.indices.push_back(first + part.indices[i]);
    // A mirror turns counter-clockwise into clockwise; swapping two corners undoes that.
    into.indices.push_back(first + part.indices[mirrors ? i + 2 : i + 1]);
    into.indices.push_back(first + part.indices[mirrors ? i + 1 : i + 2]);
  }
}

}  // namespace sim4cv::render
