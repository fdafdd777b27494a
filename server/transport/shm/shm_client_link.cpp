#include "server/transport/shm/shm_client_link.h"

#include "server/session/client_protocol.h"

namespace sim4cv::transport {

ShmClientLink::ShmClientLink(std::shared_ptr<ShmClientArea> area, session::Counters& counters,
                             std::function<void()> on_fatal)
    : area_(std::move(area)), counters_(counters), on_fatal_(std::move(on_fatal)) {}

void ShmClientLink::OfferFrame(const session::FrameRef&) { frames_offered_.fetch_add(1, std::memory_order_relaxed); }

void ShmClientLink::OfferReply(proto::Envelope reply) {
  if (Send(reply)) on_fatal_();
}

uint64_t ShmClientLink::TakeFramesOffered() { return frames_offered_.exchange(0, std::memory_order_relaxed); }

void ShmClientLink::Reply(const proto::Envelope& reply) { Send(reply); }

bool ShmClientLink::Send(const proto::Envelope& reply) {
  std::lock_guard lock(mutex_);
  if (closed_) return false;  // the session is over: nobody to answer
  Write(reply);
  if (!session::ClientProtocol::EndsConnection(reply)) return false;
  closed_ = true;  // nothing goes out after a fatal Error
  fatal_message_ = reply.error().message();
  return true;
}

void ShmClientLink::Close() {
  std::lock_guard lock(mutex_);
  closed_ = true;
}

void ShmClientLink::EndAttachment(const proto::Envelope* error) {
  std::lock_guard lock(mutex_);
  if (!closed_ && error) Write(*error);
  closed_ = true;
  area_->MarkClosed();
}

bool ShmClientLink::closed() const {
  std::lock_guard lock(mutex_);
  return closed_;
}

std::string ShmClientLink::fatal_message() const {
  std::lock_guard lock(mutex_);
  return fatal_message_;
}

void ShmClientLink::Write(const proto::Envelope& reply) {
  const ShmClientArea::Written written = area_->Write(reply);
  if (written == ShmClientArea::Written::kDone) return;
  counters_.Add("shm.responses_too_large");
  const std::string why =
      written == ShmClientArea::Written::kTooLarge
          ? "the reply is " + std::to_string(reply.ByteSizeLong()) + " bytes, more than the " +
                std::to_string(shm::kShmSocketResponseBytes) + " a shared-memory response may have; ask for it over TCP"
          : "the reply is " + std::to_string(reply.ByteSizeLong()) +
                " bytes, too long for the response ring, and this client's socket still holds earlier long replies "
                "it has not read; read them (or ask over TCP)";
  proto::Envelope refusal;
  session::ClientProtocol::Refuse(proto::ERROR_CODE_INVALID_STATE, why, false, refusal);
  area_->Write(refusal);
}

}  // namespace sim4cv::transport
