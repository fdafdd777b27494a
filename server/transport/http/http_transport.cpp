#include "server/transport/http/http_transport.h"

// clang-format off
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
// clang-format on

#include <boost/asio.hpp>
#include <chrono>
#include <thread>

#include "server/common/diagnostics.h"
#include "server/transport/http/http_connection.h"
#include "server/transport/http/http_hub.h"
#include "server/transport/tcp/descriptor_limit.h"

namespace sim4cv::transport {
namespace {

namespace asio = boost::asio;

class HttpTransport : public Transport {
 public:
  explicit HttpTransport(const HttpOptions& options)
      : options_(options), files_(options.studio_dir), hub_(options_, files_), acceptor_(io_), accept_retry_(io_) {
    // (hub_ only keeps references to options_ and files_, built before it.)
    EnsureDescriptorsFor(options.max_clients + options.other_connections,
                         "--max-clients " + std::to_string(options.other_connections) + " plus --http-max-clients " +
                             std::to_string(options.max_clients));
    boost::system::error_code error;
    const auto address = asio::ip::make_address(options.bind_address, error);
    if (error) {
      throw std::runtime_error("--http-bind '" + options.bind_address + "' is not an IP address: " + error.message());
    }
    const asio::ip::tcp::endpoint endpoint(address, options.port);
    acceptor_.open(endpoint.protocol());
    acceptor_.set_option(asio::socket_base::reuse_address(true));
    acceptor_.bind(endpoint, error);
    if (error) {
      throw std::runtime_error("cannot listen on HTTP " + options.bind_address + ":" + std::to_string(options.port) +
                               ": " + error.message() + " (pick another --http-port, or 0 for any free port)");
    }
    acceptor_.listen();
    port_ = acceptor_.local_endpoint().port();
    if (!address.is_loopback()) {
      LOG_WARNING("the studio listens on " << options.bind_address << ":" << port_
                                           << ", beyond this machine: anyone who reaches it can drive the simulation "
                                              "(docs/studio.md, \"Security\")");
    }
  }

  ~HttpTransport() override { Stop(); }

  proto::TransportInfo info() const override {
    proto::TransportInfo info;
    info.set_kind(proto::TRANSPORT_KIND_WEBSOCKET);
    info.set_address(std::to_string(port_));  // the WebSocket is at ws://HOST:PORT/ws
    return info;
  }

  std::string listening_field() const override { return "http=" + std::to_string(port_); }

  void Start(const session::ServerContext& context) override {
    hub_.context = &context;
    LOG_INFO("studio at http://" << options_.bind_address << ":" << port_ << "/ (" << files_.count() << " files from "
                                 << options_.studio_dir << ")");
    Accept();
    thread_ = std::thread([this] { io_.run(); });
  }

  void Stop() override {
    if (!thread_.joinable()) return;
    asio::post(io_, [this] {
      boost::system::error_code ignored;
      acceptor_.close(ignored);
      accept_retry_.cancel();
      hub_.CloseAll();
    });
    thread_.join();
  }

 private:
  void Accept() {
    acceptor_.async_accept([this](boost::system::error_code error, asio::ip::tcp::socket socket) {
      if (error == asio::error::operation_aborted || !acceptor_.is_open()) return;
      if (error) return AcceptFailed(error);
      const bool over_capacity = hub_.Count(false) >= options_.max_clients;
      if (over_capacity && hub_.Count(true) >= limits::kMaxHttpRejecting) {
        // A flood: closing unanswered keeps the descriptors it can hold bounded.
        boost::system::error_code ignored;
        socket.close(ignored);
      } else {
        const uint64_t key = ++next_key_;
        auto connection = std::make_shared<HttpConnection>(std::move(socket), key, hub_, over_capacity);
        hub_.Register(key, connection, over_capacity);
        connection->Start();
      }
      Accept();
    });
  }

  // As TCP's accept loop: out of descriptors, wait kAcceptRetryMs instead of
  // spinning, and warn once per kAcceptErrorLogIntervalMs.
  void AcceptFailed(const boost::system::error_code& error) {
    using Clock = std::chrono::steady_clock;
    ++accept_failures_;
    const auto now = Clock::now();
    if (now >= next_accept_warning_) {
      LOG_WARNING("HTTP accept failed " << accept_failures_ << " time(s) in the last "
                                        << limits::kAcceptErrorLogIntervalMs / 1000 << " s, last: " << error.message()
                                        << "; retrying every " << limits::kAcceptRetryMs << " ms (" << DescriptorUsage()
                                        << ")");
      accept_failures_ = 0;
      next_accept_warning_ = now + std::chrono::milliseconds(limits::kAcceptErrorLogIntervalMs);
    }
    accept_retry_.expires_after(std::chrono::milliseconds(limits::kAcceptRetryMs));
    accept_retry_.async_wait([this](boost::system::error_code wait_error) {
      if (!wait_error && acceptor_.is_open()) Accept();
    });
  }

  HttpOptions options_;
  StaticFiles files_;
  asio::io_context io_;  // before the hub: its sessions' sockets go first
  HttpHub hub_;
  asio::ip::tcp::acceptor acceptor_;
  asio::steady_timer accept_retry_;
  uint64_t accept_failures_ = 0;
  std::chrono::steady_clock::time_point next_accept_warning_{};
  uint16_t port_ = 0;
  uint64_t next_key_ = 0;
  std::thread thread_;
};

}  // namespace

std::unique_ptr<Transport> MakeHttpTransport(const HttpOptions& options) {
  return std::make_unique<HttpTransport>(options);
}

}  // namespace sim4cv::transport
