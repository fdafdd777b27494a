#include "server/transport/tcp/tcp_transport.h"

#include <boost/asio.hpp>
#include <map>
#include <thread>
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it

#include "server/common/diagnostics.h"
#include "server/common/limits.h"
#include "server/transport/tcp/descriptor_limit.h"
#include "server/transport/tcp/listener.h"
#include "server/transport/tcp/tcp_session.h"

namespace sim4cv::transport {
namespace {

namespace asio = boost::asio;

class TcpTransport : public Transport {
 public:
  explicit TcpTransport(const TcpOptions& options)
      : options_(options),
        // The descriptor limit is raised before the socket is bound (the comma operator).
        listener_((EnsureDescriptorsFor(options.max_clients), io_), options.bind_address, options.port, "TCP", "--bind",
                  "--tcp-port") {}

  ~TcpTransport() override { Stop(); }

  proto::TransportInfo info() const override {
    proto::TransportInfo info;
    info.set_kind(proto::TRANSPORT_KIND_TCP);
    info.set_address(std::to_string(listener_.port()));
    return info;
  }

  std::string listening_field() const override { return "tcp=" + std::to_string(listener_.port()); }

  void Start(const session::ServerContext& context) override {
    context_ = &context;
    listener_.Start([this](asio::ip::tcp::socket socket) { Accepted(std::move(socket)); });
    thread_ = std::thread([this] { io_.run(); });
  }

  void Stop() override {
    if (!thread_.joinable()) return;
    asio::post(io_, [this] {
      listener_.Close();
      // Close() erases from sessions_ through the callback, so close copies.
      auto open = sessions_;
      for (auto& [id, session] : open) session->Close();
    });
    // Outstanding handlers finish (they see closed sockets), then run() returns.
    thread_.join();
  }

 private:
  void Accepted(asio::ip::tcp::socket socket) {
    const session::ClientId id = session::NewClientId();
    auto session = std::make_shared<TcpSession>(std::move(socket), id, *context_, options_,
                                                [this](session::ClientId closed) { sessions_.erase(closed); });
    if (sessions_.size() >= options_.max_clients) ReclaimStalestHalfOpen();
    if (sessions_.size() >= options_.max_clients) {
      session->Reject(proto::ERROR_CODE_TOO_MANY_CLIENTS,
                      "the daemon already serves " + std::to_string(sessions_.size()) +
                          " clients (daemon flag --max-clients); try again after one disconnects");
    } else {
      sessions_.emplace(id, session);
      LOG_INFO("client " << id << " connected over TCP");
      session->Start();
    }
  }

  // At capacity, the oldest connection that has not said Hello makes room
  // for the newcomer (ids grow with time: the map's first is the oldest): a
  // process that keeps reconnecting half-sent requests cannot hold every
  // slot against clients that complete theirs.
  void ReclaimStalestHalfOpen() {
    for (const auto& [id, session] : sessions_) {
      if (session->handshaken()) continue;
      LOG_INFO("client " << id << " closed: it had not completed its Hello, and a new connection needs its slot "
                         "(--max-clients " << options_.max_clients << ")");
      const std::shared_ptr<TcpSession> stalest = session;  // Close() erases it from the map
      stalest->Close();
      return;
    }
  }

  TcpOptions options_;
  asio::io_context io_;
  Listener listener_;
  const session::ServerContext* context_ = nullptr;
  std::map<session::ClientId, std::shared_ptr<TcpSession>> sessions_;  // Asio thread only
  std::thread thread_;
};

}  // namespace

std::unique_ptr<Transport> MakeTcpTransport(const TcpOptions& options) {
  return std::make_unique<TcpTransport>(options);
}

}  // namespace sim4cv::transport
