// SimThread's run log requests: StartLog and StopLog (docs/logs.md, "Logs
// started by a client"). The sim thread owns the RunLogger, so a log starts
// and stops between two frames: its header holds the world of the frame
// before its first record, and its last record is the last frame before
// StopLog.
#include "server/common/diagnostics.h"
#include "server/daemon/named_files.h"
#include "server/daemon/sim_thread.h"

namespace sim4cv::daemon {

void SimThread::ConfigureLog(const proto::Configure& request, proto::Configured& answer) {
  const bool from_flag = !config_.log_file.empty();
  if (request.has_start_log()) {
    const proto::StartLog& start = request.start_log();
    if (logger_) {
      throw ConfigureError(proto::ERROR_CODE_INVALID_STATE,
                           "StartLog: the daemon already writes the run log " + sim_.log_file() +
                               (from_flag ? " (--log), which ends with the daemon" : "; StopLog first"));
    }
    Config setup = config_;  // what the header records: the world as it is now
    NewLogFile file = CreateLogFile(config_.logs_dir, start.name(), start.overwrite());
    setup.log_file = file.path;
    setup.log_label = start.label();
    setup.conditions = sim_.conditions();
    setup.randomize_seed = sim_.randomize_seed();
    setup.randomize_every_frames = sim_.randomize_every();
    try {
      logger_ = std::make_unique<RunLogger>(std::move(file.fd), setup, sim_.scene(), sim_.state(), counters_);
    } catch (const std::exception& error) {
      file.Discard();  // no empty or headless log left behind
      throw ConfigureError(proto::ERROR_CODE_IO, std::string("StartLog: ") + error.what());
    }
    scheduler_.SetObserver(logger_.get());
    sim_.SetLogFile(setup.log_file);
    answer.set_log_file(setup.log_file);
    LOG_INFO("run log " << setup.log_file << " started by a client after frame " << sim_.state().frame_id);
  } else {
    if (!logger_ || from_flag) {
      throw ConfigureError(proto::ERROR_CODE_INVALID_STATE,
                           from_flag ? "StopLog: the run log --log " + config_.log_file +
                                           " ends with the daemon; StopLog stops only a log StartLog began"
                                     : std::string("StopLog: no run log is being written (StartLog starts one)"));
    }
    scheduler_.SetObserver(nullptr);
    logger_->Close();  // logs what it holds
    logger_.reset();
    answer.set_log_file(sim_.log_file());
    sim_.SetLogFile("");
  }
  sim_.FillWorldInfo(*answer.mutable_world());
}

}  // namespace sim4cv::daemon
