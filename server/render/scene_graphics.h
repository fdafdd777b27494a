// Turns the simulation's Scene and State into what the Renderer draws: the
// meshes (built once), the static draw items, the labelled objects' 3D
// ground truth, and per frame the moving bodies' items and each camera's view.
#pragma once

#include <cstdint>
#include <vector>

#include "server/render/ground_truth.h"
#include "server/render/object_catalog.h"
#include "server/render/render_types.h"
#include "server/sim/scene.h"
#include "server/sim/state.h"

namespace sim4cv::render {

class SceneGraphics {
 public:
  explicit SceneGraphics(const sim::Scene& scene);

  const std::vector<Mesh>& meshes() const { return meshes_; }

  // Static items followed by the moving bodies at `state`. The returned
  // vector is owned by this object and reused: no allocation per frame.
  const std::vector<DrawItem>& DrawItems(const sim::State& state);

  // Labelled objects (instance id, class) in instance-id order; the renderer
  // fills in their unoccluded pixel counts.
  std::vector<LabelledObject>& labelled_objects() { return labelled_; }

  // Class, pose and 3D box of every labelled object (built once).
  const ObjectCatalog& catalog() const { return catalog_; }

  // The view of scene camera `camera_index` at `state`.
  CameraView CameraAt(std::size_t camera_index, const sim::State& state) const;

  // One more than the largest instance id in the scene.
  std::size_t instance_id_bound() const { return instance_id_bound_; }

 private:
  const sim::Scene& scene_;
  std::vector<Mesh> meshes_;
  std::vector<DrawItem> items_;
  std::size_t static_item_count_ = 0;
  MeshId car_mesh_ = 0, uav_mesh_ = 0;
  std::vector<LabelledObject> labelled_;
  ObjectCatalog catalog_;
  std::size_t instance_id_bound_ = 0;
};

}  // namespace sim4cv::render
