// SimThread's run log requests: StartLog and StopLog (docs/logs.md, "Logs
// started by a client"). The sim thread owns the RunLogger, so a log starts
// and stops between two frames: its header holds the world of the frame
// before its first record, and its last record is the last frame before
// StopLog, before its client left (unless StartLog.detach), or before a cap
// or a failed write closed it.
#include "server/common/diagnostics.h"
#include "server/daemon/named_files.h"
#include "server/daemon/sim_thread.h"
#include "server/session/client_protocol.h"

namespace sim4cv::daemon {

void SimThread::ConfigureLog(session::ClientId client, const std::shared_ptr<session::ClientLink>& link,
                             const proto::Configure& request, proto::Configured& answer) {
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
    log_owner_ = client;
    log_owner_link_ = link;
    log_detached_ = start.detach();
    LOG_INFO("run log " << setup.log_file << " started by client " << client << " after frame "
                        << sim_.state().frame_id
                        << (start.detach() ? " (detached: it outlives the client)" : " (it ends when the client leaves)"));
  } else {
    if (!logger_ || from_flag) {
      throw ConfigureError(proto::ERROR_CODE_INVALID_STATE,
                           from_flag ? "StopLog: the run log --log " + config_.log_file +
                                           " ends with the daemon; StopLog stops only a log StartLog began"
                                     : std::string("StopLog: no run log is being written (StartLog starts one)"));
    }
    logger_->Close();  // logs what it holds
    answer.set_log_file(sim_.log_file());
    DropLog();
  }
  sim_.FillWorldInfo(*answer.mutable_world());
}

void SimThread::AfterLogAppend() {
  if (logger_->open()) return;
  const std::optional<RunLogger::End> end = logger_->end();
  if (end && log_owner_link_) {
    proto::Envelope reply;
    session::ClientProtocol::Refuse(end->code, end->message, false, reply);
    log_owner_link_->OfferReply(std::move(reply));
  }
  DropLog();
}

void SimThread::LogOwnerLeft(session::ClientId client) {
  if (!logger_ || client != log_owner_) return;
  log_owner_link_.reset();  // nobody to tell any more
  if (log_detached_) {
    LOG_INFO("run log " << sim_.log_file() << " goes on without client " << client
                        << ", which started it with StartLog.detach");
    return;
  }
  LOG_INFO("run log " << sim_.log_file() << " closed after frame " << sim_.state().frame_id << ": client " << client
                      << ", which started it, disconnected (StartLog.detach keeps a log going without its client)");
  logger_->Close();
  DropLog();
}

void SimThread::DropLog() {
  scheduler_.SetObserver(nullptr);
  logger_.reset();
  log_owner_ = 0;
  log_owner_link_.reset();
  log_detached_ = false;
  sim_.SetLogFile("");
  PublishWorld();
}

}  // namespace sim4cv::daemon
