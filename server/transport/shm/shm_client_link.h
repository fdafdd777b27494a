// One shared-memory client's ClientLink: made by the shm thread for each of
// the client's sessions, shared with the sim thread through its Subscribe.
//
// Its frames travel through the ring (ShmRingWriter), so OfferFrame only
// counts them: each is one "frame sent" for the lockstep Step limit.
//
// Its replies go into the client's response ring (its ShmClientArea): ClientProtocol's from the
// shm thread (Reply), the sim thread's from the sim thread itself
// (OfferReply). The ring's frames are published on the sim thread as they are
// offered, so writing the reply there too is the only way it can be visible
// before the next frame without the sim thread waiting for the shm thread.
// Like publishing a frame it is a copy into shared memory and a futex wake;
// a response too long for the ring is one non-blocking send on the client's
// socket (a copy into the kernel, never a wait). A mutex keeps the area's two
// writers apart, held by either only while one response is written.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "server/session/client_link.h"
#include "server/session/counters.h"
#include "server/transport/shm/shm_client_area.h"

namespace sim4cv::transport {

class ShmClientLink : public session::ClientLink {
 public:
  // Writes into `area`'s response ring. `on_fatal` runs on the sim thread
  // after OfferReply has sent a fatal Error (and closed this link): the shm
  // thread must then end the session, as after ClientProtocol's fatal Errors.
  ShmClientLink(std::shared_ptr<ShmClientArea> area, session::Counters& counters, std::function<void()> on_fatal);

  // Sim thread.
  void OfferFrame(const session::FrameRef& frame) override;
  void OfferReply(proto::Envelope reply) override;
  // Its pixels are the ring's.
  bool SendsFramePixels() const override { return false; }

  // Shm thread. Frames offered since the last call.
  uint64_t TakeFramesOffered();
  // Writes one of ClientProtocol's replies. Like OfferReply, it drops what
  // comes once the link is closed, and a fatal Error closes it.
  void Reply(const proto::Envelope& reply);
  // The session is over: nothing more is written through this link (the
  // client's next session gets a new one). Idempotent.
  void Close();
  // The client's attachment is over: writes `error` if the link is still
  // open and it is set, closes the link and marks the area closed, so the
  // client learns it at once. Idempotent.
  void EndAttachment(const proto::Envelope* error);
  // True once closed, by Close or by a fatal Error.
  bool closed() const;
  // The message of the fatal Error that closed the link, for the log.
  std::string fatal_message() const;

 private:
  // Writes `reply` unless the link is closed. True if it was a fatal Error,
  // which closed the link.
  bool Send(const proto::Envelope& reply);
  // With mutex_ held, open: writes `reply`, or an Error naming its size if it
  // cannot be sent (longer than a shared-memory response may be, or the
  // client's socket is full of long responses it has not read).
  void Write(const proto::Envelope& reply);

  std::shared_ptr<ShmClientArea> area_;  // kept mapped while the sim thread may still hold this link
  session::Counters& counters_;
  std::function<void()> on_fatal_;
  std::atomic<uint64_t> frames_offered_{0};

  mutable std::mutex mutex_;
  bool closed_ = false;        // guarded by mutex_
  std::string fatal_message_;  // guarded by mutex_
};

}  // namespace sim4cv::transport
