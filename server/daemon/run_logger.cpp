#include "server/daemon/run_logger.h"

#include <chrono>
#include <sstream>

#include "server/common/check.h"
#include "server/common/diagnostics.h"
#include "server/sim/log/replay_check.h"
#include "server/sim/traffic_bodies.h"

namespace sim4cv::daemon {
namespace {

static_assert(sim::InfoOf(sim::EntityKind::kCar).log_class == runlog::kObjectClassCar &&
                  sim::InfoOf(sim::EntityKind::kUav).log_class == runlog::kObjectClassUav &&
                  sim::InfoOf(sim::EntityKind::kPedestrian).log_class == runlog::kObjectClassPedestrian,
              "the entity kinds' run-log classes (sim/entity_kinds.h) are the log format's");

uint16_t LogClassOf(sim::EntityKind kind) { return sim::InfoOf(kind).log_class; }

runlog::RunLogHeader MakeHeader(const Config& config, const sim::Scene& scene, const sim::State& initial) {
  runlog::RunLogHeader header;
  header.creator = "sim4cvd " SIM4CV_VERSION;
  header.label = config.log_label.empty() ? scene.name : config.log_label;
  header.scene_name = scene.name;
  header.map_path = scene.map_path;
  header.physics_hz = config.physics_hz;
  header.frame_hz = config.frame_hz;
  header.seed = config.seed;
  // Fixed while logging (SetConditions is refused), or drawn from a seed:
  // every frame's conditions follow from it (conditions::Randomized).
  header.conditions = config.randomize_seed == 0
                          ? conditions::Describe(config.conditions)
                          : "randomised from seed " + std::to_string(config.randomize_seed) +
                                (config.randomize_every_frames == 0
                                     ? std::string(", once per episode")
                                     : ", every " + std::to_string(config.randomize_every_frames) + " frames") +
                                ", " + std::string(conditions::QualityName(config.conditions.quality)) + " quality";
  // The entities and cameras at the start; records hold every entity
  // present at their frame, so ones spawned later appear there by id.
  for (const sim::Entity& entity : initial.entities) {
    header.entities.push_back({entity.id, entity.name, static_cast<uint16_t>(entity.kind), LogClassOf(entity.kind)});
  }
  // Traffic (docs/maps.md, "Traffic"): every moving car and walker, so that
  // a replay shows it where it was.
  const traffic::TrafficIds ids = sim::TrafficIdsOf(scene);
  for (uint32_t id = ids.cars; id < ids.walkers; ++id) {
    header.entities.push_back(
        {id, "traffic_car_" + std::to_string(id - ids.cars), runlog::kEntityKindCar, runlog::kObjectClassCar});
  }
  for (uint32_t id = ids.walkers; id < ids.end; ++id) {
    header.entities.push_back({id, "walker_" + std::to_string(id - ids.walkers), runlog::kEntityKindPedestrian,
                               runlog::kObjectClassPedestrian});
  }
  for (const auto& camera : scene.cameras) {
    const sim::Entity* mount = initial.FindByName(camera.mounted_on);
    header.cameras.push_back({camera.name, mount ? mount->id : 0u, camera.width, camera.height});
  }
  return header;
}

}  // namespace

RunLogger::RunLogger(const Config& config, const sim::Scene& scene, const sim::State& initial,
                     session::Counters& counters)
    : counters_(counters),
      traffic_ids_(sim::TrafficIdsOf(scene)),
      writer_(std::make_unique<runlog::RunLogWriter>(config.log_file, MakeHeader(config, scene, initial))),
      max_bytes_(config.log_max_bytes),
      max_seconds_(config.log_max_seconds),
      start_sim_time_(initial.sim_time) {}

RunLogger::RunLogger(Fd log_fd, const Config& config, const sim::Scene& scene, const sim::State& initial,
                     session::Counters& counters)
    : counters_(counters),
      traffic_ids_(sim::TrafficIdsOf(scene)),
      writer_(std::make_unique<runlog::RunLogWriter>(log_fd.release(), config.log_file,
                                                     MakeHeader(config, scene, initial))),
      max_bytes_(config.log_max_bytes),
      max_seconds_(config.log_max_seconds),
      start_sim_time_(initial.sim_time) {}

void RunLogger::OfferFrame(const session::FrameRef& frame) {
  for (const render::GroundTruthBox& box : frame->boxes) {
    if (box.instance != sim::kCarEntityId) continue;
    record_.ground_truth.push_back({static_cast<uint16_t>(frame->camera_index), box.instance, box.x, box.y, box.width,
                                    box.height, box.visibility});
  }
}

void RunLogger::Append(const sim::State& state, const session::Scheduler& scheduler) {
  if (writer_) {
    const auto start = std::chrono::steady_clock::now();
    record_.frame_id = state.frame_id;
    record_.sim_time = state.sim_time;
    for (const sim::Entity& entity : state.entities) record_.entities.push_back({entity.id, entity.body});
    for (std::size_t i = 0; i < state.traffic.cars.size(); ++i) {
      record_.entities.push_back({traffic_ids_.cars + static_cast<uint32_t>(i), sim::BodyOf(state.traffic.cars[i])});
    }
    for (std::size_t i = 0; i < state.traffic.walkers.size(); ++i) {
      record_.entities.push_back(
          {traffic_ids_.walkers + static_cast<uint32_t>(i), sim::BodyOf(state.traffic.walkers[i])});
    }
    // State keeps each client's latest report until it sends another, so a
    // box recurs in every record until replaced; its frame_id tells them apart.
    for (const sim::TrackerReport& report : state.tracker_reports) {
      const std::optional<uint32_t> camera = scheduler.CameraOf(report.client_id);
      record_.tracker_boxes.push_back({camera ? static_cast<uint16_t>(*camera) : runlog::kNoCamera, report});
    }
    for (const sim::Entity& entity : state.entities) {
      if (entity.kind == sim::EntityKind::kCar) record_.controls.push_back({entity.id, entity.car_command});
    }
    try {
      writer_->Append(record_);
    } catch (const std::exception& error) {
      Fail(error);
    }
    if (writer_ && writer_->bytes_written() >= max_bytes_) {
      EndAtCap("it reached " + std::to_string(writer_->bytes_written()) + " bytes (daemon flag --log-max-bytes " +
                   std::to_string(max_bytes_) + ")",
               state.frame_id);
    } else if (writer_ && state.sim_time - start_sim_time_ >= max_seconds_) {
      std::ostringstream cap;
      cap << "its records span " << state.sim_time - start_sim_time_
          << " simulated seconds (daemon flag --log-max-seconds " << max_seconds_ << ")";
      EndAtCap(cap.str(), state.frame_id);
    }
    append_ns_ +=
        std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count();
  }
  record_.Clear();
}

void RunLogger::Close() {
  if (!writer_) return;
  const uint64_t records = writer_->records_written();
  const uint64_t bytes = writer_->bytes_written();
  const std::string path = writer_->path();
  try {
    writer_->Close();
  } catch (const std::exception& error) {
    Fail(error);
    return;
  }
  writer_.reset();
  LOG_INFO("run log " << path << ": " << records << " records, " << bytes << " bytes, "
                      << (records ? static_cast<double>(append_ns_) / 1e3 / static_cast<double>(records) : 0.0)
                      << " us per record on the sim thread");
}

void RunLogger::Fail(const std::exception& error) {
  // The writer has cut the file back to its last whole record, so the log
  // stays readable; the simulation must not stop for a full disk.
  LOG_ERROR(error.what() << "; run logging stopped, the simulation goes on");
  counters_.Add("log.write_errors");
  end_ = End{proto::ERROR_CODE_IO, std::string(error.what()) +
                                       "; the log was closed, its records so far are whole and readable and the "
                                       "simulation goes on (StartLog starts a new log)"};
  writer_.reset();
}

void RunLogger::EndAtCap(const std::string& cap, uint64_t frame_id) {
  const std::string path = writer_->path();
  Close();
  if (end_) return;  // closing failed: Fail said why
  counters_.Add("log.capped");
  end_ = End{proto::ERROR_CODE_INVALID_STATE, "the run log " + path + " was closed after frame " +
                                                  std::to_string(frame_id) + ": " + cap +
                                                  "; it is whole and readable (StartLog starts a new log)"};
  LOG_WARNING(end_->message);
}

std::shared_ptr<const runlog::ReplayTrack> LoadReplayTrack(const Config& config, const sim::Scene& scene) {
  auto track = std::make_shared<const runlog::ReplayTrack>(runlog::ReplayTrack::Load(config.replay_file));
  try {
    runlog::CheckReplayValues(*track);  // before any of it reaches the World or a camera
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument("--replay " + config.replay_file + ": " + error.what() +
                                "; a log is replayed only if every pose is one a client could set");
  }
  const runlog::RunLogHeader& header = track->header();
  SIM4CV_THROW_UNLESS(header.scene_name == scene.name,
                      config.replay_file << " was recorded on scene '" << header.scene_name << "', not '" << scene.name
                                         << "'; start with its --map or --scene");
  SIM4CV_THROW_UNLESS(header.frame_hz == config.frame_hz, config.replay_file << " was recorded at --frame-hz "
                                                                             << header.frame_hz << ", not "
                                                                             << config.frame_hz);
  if (track->empty()) {
    LOG_WARNING("replay log " << config.replay_file << " holds no frames; the car and the UAV stay where they start");
  } else {
    LOG_INFO("replaying frames " << track->frame_id(0) << ".." << track->frame_id(track->frame_count() - 1) << " of "
                                 << config.replay_file);
  }
  return track;
}

}  // namespace sim4cv::daemon
