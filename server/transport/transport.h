// One interface for every way clients reach the daemon (after LibCarla's
// streaming facade over detail/tcp): each adapter owns its sockets and
// threads, decodes bytes into Envelopes, lets session::ClientProtocol decide
// what they mean, and delivers frames from its sessions' mailboxes. Adding a
// transport is a new folder and one line in the daemon.
#pragma once

#include <string>

#include "server/session/server_context.h"
#include "sim4cv.pb.h"

namespace sim4cv::transport {

class Transport {
 public:
  virtual ~Transport() = default;
  // Kind and address for Welcome.transports.
  virtual proto::TransportInfo info() const = 0;
  // This transport's field of the listening line, e.g. "tcp=40123".
  virtual std::string listening_field() const = 0;
  // Starts serving. `context` (including its Welcome) is final by now and
  // outlives the transport.
  virtual void Start(const session::ServerContext& context) = 0;
  // Closes every connection and joins the transport's threads.
  virtual void Stop() = 0;
};

}  // namespace sim4cv::transport
