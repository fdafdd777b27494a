// What the renderer draws of a map's traffic (server/sim/traffic): parked
// cars and traffic lights as static labelled objects, and per frame the lit
// lamp of every light, the moving cars and the walkers (walker_looks.h). Ids follow the map's
// own objects: parked cars, then lights, then moving cars, then walkers.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <vector>

#include "server/render/ground_truth.h"
#include "server/render/object_catalog.h"
#include "server/render/render_types.h"
#include "server/render/traffic_meshes.h"
#include "server/render/walker_looks.h"
#include "server/sim/traffic/traffic_ids.h"
#include "server/sim/traffic/traffic_state.h"

namespace sim4cv::render {

class TrafficGraphics {
 public:
  // Adds a mesh to the scene's list and returns its id.
  using AddMesh = std::function<MeshId(Mesh mesh)>;
  // Adds a static draw item (labelled unless `instance` is kUnlabelled).
  using AddStatic = std::function<void(MeshId mesh, InstanceId instance, uint32_t object_class,
                                       const Eigen::Matrix4f& world_from_model)>;

  // `car_half_extents`: the simulated car's box, which traffic cars share;
  // `car_centre_height`: where that box's centre stands at rest;
  // `walker_looks`: the scene's walker meshes (it must outlive this).
  TrafficGraphics(const traffic::TrafficPlan& plan, const traffic::TrafficIds& ids,
                  const Eigen::Vector3d& car_half_extents, double car_centre_height, const WalkerLooks& walker_looks,
                  const AddMesh& add_mesh, const AddStatic& add_static);

  // Appends the lit lamps, moving cars and walkers at `state` and `sim_time`
  // (ids ascending, after every static one). No allocation once warm.
  void Append(const traffic::TrafficState& state, double sim_time, std::vector<DrawItem>& items,
              std::vector<LabelledObject>& labelled, std::vector<MovingObject>& moving) const;

  // One more than the largest id it labels.
  InstanceId id_bound() const { return id_bound_; }

 private:
  static constexpr int kCarVariants = 24;  // colour i and style i % kCarStyleCount

  const traffic::TrafficPlan& plan_;
  Eigen::Vector3d car_half_extents_;
  double car_centre_height_;
  std::vector<Eigen::Matrix4f> light_poses_;
  std::vector<InstanceId> light_ids_;
  std::array<MeshId, 3> lamp_meshes_{};  // by traffic::Signal
  std::array<MeshId, kCarVariants> car_meshes_{};
  const WalkerLooks& walker_looks_;
  InstanceId first_moving_car_ = 0, first_walker_ = 0, id_bound_ = 0;
};

}  // namespace sim4cv::render
