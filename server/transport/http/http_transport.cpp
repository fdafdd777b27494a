#include "server/transport/http/http_transport.h"

// clang-format off
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
// clang-format on

#include <boost/asio.hpp>
#include <thread>

#include "server/common/diagnostics.h"
#include "server/transport/http/http_connection.h"
#include "server/transport/http/http_hub.h"
#include "server/transport/tcp/descriptor_limit.h"
#include "server/transport/tcp/listener.h"

namespace sim4cv::transport {
namespace {

namespace asio = boost::asio;

class HttpTransport : public Transport {
 public:
  explicit HttpTransport(const HttpOptions& options)
      : options_(options),
        files_(options.studio_dir),
        hub_(options_, files_),  // (it only keeps references to options_ and files_, built before it)
        // The descriptor limit is raised before the socket is bound (the comma operator).
        listener_((EnsureDescriptorsFor(options.max_clients + options.other_connections,
                                        "--max-clients " + std::to_string(options.other_connections) +
                                            " plus --http-max-clients " + std::to_string(options.max_clients)),
                   io_),
                  options.bind_address, options.port, "HTTP", "--http-bind", "--http-port") {
    if (!listener_.loopback()) {
      LOG_WARNING("the studio listens on " << options.bind_address << ":" << listener_.port()
                                           << ", beyond this machine: anyone who reaches it can drive the simulation "
                                              "(docs/studio.md, \"Security\")");
    }
  }

  ~HttpTransport() override { Stop(); }

  proto::TransportInfo info() const override {
    proto::TransportInfo info;
    info.set_kind(proto::TRANSPORT_KIND_WEBSOCKET);
    info.set_address(std::to_string(listener_.port()));  // the WebSocket is at ws://HOST:PORT/ws
    return info;
  }

  std::string listening_field() const override { return "http=" + std::to_string(listener_.port()); }

  void Start(const session::ServerContext& context) override {
    hub_.context = &context;
    LOG_INFO("studio at http://" << options_.bind_address << ":" << listener_.port() << "/ (" << files_.count()
                                 << " files from " << options_.studio_dir << ")");
    listener_.Start([this](asio::ip::tcp::socket socket) { Accepted(std::move(socket)); });
    thread_ = std::thread([this] { io_.run(); });
  }

  void Stop() override {
    if (!thread_.joinable()) return;
    asio::post(io_, [this] {
      listener_.Close();
      hub_.CloseAll();
    });
    thread_.join();
  }

 private:
  void Accepted(asio::ip::tcp::socket socket) {
    if (hub_.Count(false) >= options_.max_clients && hub_.ReclaimStalestHalfOpen()) {
      LOG_INFO("closed the oldest HTTP connection that had completed no request, for a new one (--http-max-clients "
               << options_.max_clients << ")");
    }
    const bool over_capacity = hub_.Count(false) >= options_.max_clients;
    if (over_capacity && hub_.Count(true) >= limits::kMaxHttpRejecting) {
      // A flood: closing unanswered keeps the descriptors it can hold bounded.
      boost::system::error_code ignored;
      socket.close(ignored);
      return;
    }
    const uint64_t key = ++next_key_;
    auto connection = std::make_shared<HttpConnection>(std::move(socket), key, hub_, over_capacity);
    hub_.Register(key, connection, over_capacity);
    connection->Start();
  }

  HttpOptions options_;
  StaticFiles files_;
  asio::io_context io_;  // before the hub: its sessions' sockets go first
  HttpHub hub_;
  Listener listener_;
  uint64_t next_key_ = 0;
  std::thread thread_;
};

}  // namespace

std::unique_ptr<Transport> MakeHttpTransport(const HttpOptions& options) {
  return std::make_unique<HttpTransport>(options);
}

}  // namespace sim4cv::transport
