// How walkers look: one of the packaged people (people_bundle.h), chosen by
// the walker's instance id, posed rigidly with a gentle gait sway; or, in a
// build without the people bundle, the procedural walker with swinging box
// limbs (traffic_meshes.h). Shared by the simulated pedestrians
// (SceneGraphics) and the traffic's walkers (TrafficGraphics).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "server/render/people_bundle.h"
#include "server/render/render_types.h"
#include "server/render/traffic_meshes.h"

namespace sim4cv::render {

// The largest lean of a walking person, radians (1.5 degrees): side to side
// with its steps, and forward at full speed. Small enough that every packaged
// person stays inside kPedestrianBox (walker_looks_test.cpp).
inline constexpr double kMaxSway = 0.026;
// A packaged person is drawn with its far mesh (Person::far) when its
// bounding sphere spans fewer rows than this: below the 96 px walkers the
// realism probe counts, where the lighter mesh's coarser head and hands
// are a few pixels.
inline constexpr float kFarPersonBelowPx = 64.0f;

// The rigid pose of a packaged person relative to its ground pose at gait
// `phase` (GaitPhase) and `speed` m/s: a roll with the steps (one sway per
// step, to the side of the foot on the ground) and a lean into the walk,
// both about the point between its feet, so the feet stay on the ground.
Eigen::Matrix4f SwayPose(double phase, double speed);

class WalkerLooks {
 public:
  using AddMesh = std::function<MeshId(Mesh mesh)>;
  // Adds the looks' meshes with `add_mesh`: `people` (by default the
  // compiled-in bundle), or if there are none the procedural figures.
  explicit WalkerLooks(const AddMesh& add_mesh, const std::vector<Person>& people = PeopleMeshes());

  // Appends the draw items of walker `id` standing at `ground_pose` (its
  // feet's point, facing +x), at ground `position`, `heading` and `speed`.
  // The look is a fixed function of `id`, so replays match.
  void Append(std::vector<DrawItem>& items, InstanceId id, const Eigen::Matrix4f& ground_pose,
              const Eigen::Vector2d& position, double heading, double speed) const;

  // Whether the walkers are packaged people (else procedural).
  bool packaged() const { return !people_.empty(); }

 private:
  static constexpr uint32_t kProceduralLooks = 6;
  struct PersonIds {
    MeshId full = 0, far = 0;
  };
  std::vector<PersonIds> people_;
  std::vector<WalkerMeshIds> procedural_;
};

}  // namespace sim4cv::render
