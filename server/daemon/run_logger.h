// The daemon's side of run logs (docs/logs.md): RunLogger writes one record
// per simulation frame on the sim thread (--log), LoadReplayTrack reads the
// log that --replay follows.
#pragma once

#include <cstdint>
#include <exception>
#include <memory>
#include <optional>
#include <string>

#include "server/common/beneath.h"
#include "server/daemon/config.h"
#include "server/session/client_link.h"
#include "server/session/counters.h"
#include "server/session/scheduler.h"
#include "server/sim/log/replay_track.h"
#include "server/sim/log/run_log_writer.h"
#include "server/sim/scene.h"
#include "server/sim/state.h"

namespace sim4cv::daemon {

// Owned by the sim thread, and the scheduler's observer (Scheduler::SetObserver):
// it sees every camera frame as it is rendered and keeps the target's
// ground-truth box; Append then writes the frame's record with one write().
// A failed write never stops the simulation: it logs one error, counts
// log.write_errors and stops logging. Reaching --log-max-bytes or
// --log-max-seconds closes the log the same way, whole. Either way end()
// then says why, for the client that started it.
class RunLogger final : public session::ClientLink {
 public:
  // Creates (truncates) config.log_file and writes the header. Throws naming
  // the file if it cannot: that refuses the start, before any frame.
  RunLogger(const Config& config, const sim::Scene& scene, const sim::State& initial, session::Counters& counters);
  // The same on a file already created and opened (StartLog's, beneath
  // --logs-dir); config.log_file names it in messages.
  RunLogger(Fd log_fd, const Config& config, const sim::Scene& scene, const sim::State& initial,
            session::Counters& counters);

  // The ground-truth box of the target (the car) in one rendered camera
  // frame of the current simulation frame, if the car is visible in it.
  void OfferFrame(const session::FrameRef& frame) override;
  // The scheduler's observer, not a client: nobody to answer.
  void OfferReply(proto::Envelope) override {}
  // Writes the current frame's record: the poses, every client's latest
  // tracker box (with the camera it subscribes to), the boxes gathered by
  // OfferFrame since the last Append, and the car's command.
  void Append(const sim::State& state, const session::Scheduler& scheduler);
  // False once closed, after a write failed or at a cap.
  bool open() const { return writer_ != nullptr; }
  // Why the log ended by itself (a failed write, a cap); nullopt while open
  // and after Close.
  struct End {
    proto::ErrorCode code;  // IO for a failed write, INVALID_STATE for a cap
    std::string message;    // names the file and the cause
  };
  const std::optional<End>& end() const { return end_; }
  // Closes the file and logs what was written and what it cost the sim
  // thread. Idempotent; the destructor closes too, silently.
  void Close();

 private:
  void Fail(const std::exception& error);
  // Closes the log at a cap: `cap` names it and its flag.
  void EndAtCap(const std::string& cap, uint64_t frame_id);

  session::Counters& counters_;
  traffic::TrafficIds traffic_ids_;               // the map traffic's entity ids, logged with the entities
  std::unique_ptr<runlog::RunLogWriter> writer_;  // null once closed or failed
  runlog::FrameLogRecord record_;                 // reused: no allocation per frame once warm
  int64_t append_ns_ = 0;                         // time spent in Append, for the closing line
  uint64_t max_bytes_;                            // --log-max-bytes
  double max_seconds_;                            // --log-max-seconds
  double start_sim_time_;                         // of the world when the log began
  std::optional<End> end_;
};

// Reads the whole of config.replay_file. Throws naming the file if it is
// missing, not a run log or damaged, holds a value a client could not send
// (runlog::CheckReplayValues: naming the record, frame, entity and field),
// or was recorded on another scene or at another frame rate (replay goes by
// frame id).
std::shared_ptr<const runlog::ReplayTrack> LoadReplayTrack(const Config& config, const sim::Scene& scene);

}  // namespace sim4cv::daemon
