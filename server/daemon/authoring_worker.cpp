#include "server/daemon/authoring_worker.h"

#include <sys/resource.h>
#include <unistd.h>

#include "server/common/diagnostics.h"
#include "server/daemon/configure_error.h"
#include "server/daemon/map_authoring.h"
#include "server/daemon/named_files.h"
#include "server/session/client_protocol.h"

namespace sim4cv::daemon {
namespace {

// What the sim thread's Simulation::Apply did for these requests, minus the world.
void Carry(const Config& config, const proto::Configure& request, proto::Configured& answer) {
  using Kind = proto::Configure::RequestCase;
  switch (request.request_case()) {
    case Kind::kListMaps:
      ListMapNames(config.maps_dir, *answer.mutable_maps());
      break;
    case Kind::kCheckMap:
      answer.set_map_text(CanonicalMapText(request.check_map().text(), "CheckMap.text"));
      break;
    case Kind::kGenerateMap:
      answer.set_map_text(GeneratedMapText(request.generate_map()));
      break;
    case Kind::kOpenMap:
      answer.set_map_text(ReadMapFile(config.maps_dir, request.open_map().name(), "OpenMap.name"));
      break;
    case Kind::kSaveMap:
      CheckMapText(request.save_map().text(), "SaveMap.text (not saved; the file on disk is unchanged)");
      WriteMapFile(config.maps_dir, request.save_map().name(), request.save_map().text(),
                   request.save_map().overwrite());
      break;
    default:
      break;  // Handles() let nothing else in
  }
}

}  // namespace

AuthoringWorker::AuthoringWorker(const Config& config, session::WorldDirectory& directory)
    : config_(config), directory_(directory), thread_([this] { Run(); }) {}

AuthoringWorker::~AuthoringWorker() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

bool AuthoringWorker::Handles(const proto::Configure& request) {
  using Kind = proto::Configure::RequestCase;
  switch (request.request_case()) {
    case Kind::kListMaps:
    case Kind::kCheckMap:
    case Kind::kGenerateMap:
    case Kind::kOpenMap:
    case Kind::kSaveMap:
      return true;
    default:
      return false;
  }
}

void AuthoringWorker::Post(session::ConfigureCommand command) {
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(std::move(command));
  }
  wake_.notify_one();
}

void AuthoringWorker::Run() {
  // Below the sim thread: authoring waits for frames, never frames for it.
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), 10);
  for (;;) {
    session::ConfigureCommand command;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;  // the links' sessions end with their transports
      command = std::move(queue_.front());
      queue_.pop_front();
    }
    Answer(command);
  }
}

void AuthoringWorker::Answer(session::ConfigureCommand& command) {
  proto::Envelope reply;
  const uint32_t request_id = command.request.request_id();
  try {
    proto::Configured& answer = *reply.mutable_configured();
    answer.set_request_id(request_id);
    Carry(config_, command.request, answer);
    *answer.mutable_world() = directory_.Get();
  } catch (const ConfigureError& refused) {
    reply.Clear();
    session::ClientProtocol::Refuse(refused.code(), refused.what(), false, reply);
    reply.mutable_error()->set_request_id(request_id);
    LOG_INFO("Configure " << request_id << " refused: " << refused.what());
  } catch (const std::exception& failed) {
    reply.Clear();
    session::ClientProtocol::Refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
                                    std::string("the daemon could not carry out this Configure (") + failed.what() +
                                        "); nothing was changed",
                                    false, reply);
    reply.mutable_error()->set_request_id(request_id);
    LOG_WARNING("Configure " << request_id << " failed: " << failed.what());
  }
  if (command.link) command.link->OfferReply(std::move(reply));
}

}  // namespace sim4cv::daemon
