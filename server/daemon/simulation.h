// Everything the sim thread simulates, apart from rendering: the current
// Scene (replaced by LoadMap), the World built from it, the State a step
// changes, and the cameras (the scene's own plus those clients added).
// Carries out Configure requests between frames. Sim thread only.
#pragma once

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "protocol/conditions.h"
#include "protocol/effects.h"
#include "server/daemon/config.h"
#include "server/daemon/configure_error.h"
#include "server/sim/scene.h"
#include "server/sim/world.h"
#include "sim4cv.pb.h"

namespace sim4cv::daemon {

class Simulation {
 public:
  Simulation(const Config& config, std::shared_ptr<const sim::Scene> scene);

  const sim::Scene& scene() const { return *scene_; }
  sim::World& world() { return *world_; }
  sim::State& state() { return state_; }
  const sim::State& state() const { return state_; }
  // In index order; a removed camera keeps its index with an empty name, so
  // subscriptions by index stay valid.
  const std::vector<sim::CameraSpec>& cameras() const { return cameras_; }
  // The camera called `name`, or -1.
  int FindCamera(const std::string& name) const;

  // What a carried-out request changed beyond State.
  struct Change {
    // LoadMap or Reset: rebuild what was built from the scene; cameras are
    // the scene's again, added ones gone.
    bool new_scene = false;
    // Indices of cameras removed (with their entity, or by RemoveCamera).
    std::vector<uint32_t> removed_cameras;
    // False for the requests that only ask (GetWorld, QueryRoad): nothing to publish.
    bool world_changed = true;
    // SetConditions: the renderer needs the new look.
    bool new_conditions = false;
    // SetEffects: the renderer needs the new camera effects.
    bool new_effects = false;
  };
  // Carries out `request` and fills `answer`, or throws ConfigureError
  // (changing nothing then). Whatever else it throws (std::bad_alloc while
  // building a map's world, say) also leaves the world as it was.
  Change Apply(const proto::Configure& request, proto::Configured& answer);
  // After an Apply: Commit() forgets the world it replaced; Undo() puts it
  // back (the scene, World, State and cameras before a LoadMap or Reset, or
  // the cameras before an AddCamera), for when the sim thread cannot build
  // the graphics the change needs. Other requests need no undo: nothing
  // the sim thread builds afterwards depends on them.
  void Commit();
  void Undo();

  // The world's entities, cameras and routes as a client sees them.
  void FillWorldInfo(proto::WorldInfo& out) const;

  // Weather, time of day and quality: the config's, then the last SetConditions',
  // or the draw of the domain randomisation in force.
  const conditions::Conditions& conditions() const { return conditions_; }
  // Once per frame, after State::frame_id advanced: true if the domain
  // randomisation drew new conditions for this frame (every N frames).
  bool AdvanceConditions();
  // Camera effects: the config's, then changed field by field by SetEffects.
  const effects::CameraEffects& effects() const { return effects_; }
  // Domain randomisation in force: seed (0: off) and period (0: per episode).
  uint64_t randomize_seed() const { return randomize_seed_; }
  uint32_t randomize_every() const { return randomize_every_; }
  // The run log being written (--log or StartLog; empty: none): while there
  // is one, LoadMap, Reset and SetConditions are refused naming it.
  const std::string& log_file() const { return log_file_; }
  void SetLogFile(std::string path) { log_file_ = std::move(path); }

 private:
  void Rebuild(std::shared_ptr<const sim::Scene> scene, Change& change);
  uint32_t Spawn(const proto::Spawn& spawn);
  void SetRoute(const proto::SetRoute& route);
  void CommandUav(const proto::CommandUav& command);
  // CommandUav.track, checked: the camera must be mounted on the UAV.
  sim::UavOrder TrackOrder(const proto::CommandUav& command) const;
  // The names of the cameras mounted on `entity`, for messages.
  std::string CamerasOn(const std::string& entity) const;
  void AddCamera(const proto::AddCamera& camera);
  // Moves a world-fixed camera; mounted ones are refused.
  void SetCameraPose(const proto::SetCameraPose& pose);
  void RemoveCamera(const std::string& name, Change& change);
  void RemoveEntity(uint32_t id, Change& change);
  void LoadMap(const proto::LoadMap& load, Change& change);
  void QueryRoad(const proto::QueryRoad& query, proto::RoadQueryResult& out) const;
  // The map's route names, quoted, for an Error ("none" without a map or routes).
  std::string RouteNames() const;
  void SetConditions(const proto::SetConditions& request, Change& change);
  void SetEffects(const proto::CameraEffects& request, Change& change);
  const sim::Entity& EntityOf(uint32_t id, const char* what) const;
  // The traffic a LoadMap asks for: its settings, else the daemon's flags.
  traffic::TrafficConfig TrafficFor(const proto::LoadMap& load) const;
  // Throws INVALID_STATE naming the log if the daemon writes one.
  void RefuseWhileLogging(const char* request, const char* why) const;

  // What Undo() restores; empty unless the last Apply replaced the world.
  struct Replaced {
    std::shared_ptr<const sim::Scene> scene;
    std::unique_ptr<sim::World> world;
    sim::State state;
    std::vector<sim::CameraSpec> cameras;
    conditions::Conditions conditions;  // a new episode may draw new ones
    uint64_t episodes = 0;
  };

  const Config& config_;
  std::optional<Replaced> replaced_;
  bool camera_added_ = false;  // by the last Apply; Undo() removes it
  std::shared_ptr<const sim::Scene> scene_;
  std::unique_ptr<sim::World> world_;
  sim::State state_;
  std::vector<sim::CameraSpec> cameras_;
  conditions::Conditions conditions_;
  effects::CameraEffects effects_;
  // Domain randomisation: seed (0: off), period (0: per episode) and the
  // episodes begun, which number the per-episode draws.
  uint64_t randomize_seed_ = 0;
  uint32_t randomize_every_ = 0;
  uint64_t episodes_ = 0;
  void StartEpisode(Change& change);
  void DrawConditions();
  std::shared_ptr<const runlog::ReplayTrack> replay_;  // --replay; kept across Reset
  std::string log_file_;
};

}  // namespace sim4cv::daemon
