#include "server/transport/tcp/tcp_transport.h"

#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
#include <boost/asio.hpp>
#include <chrono>
#include <map>
#include <thread>

#include "server/common/limits.h"
#include "server/common/diagnostics.h"
#include "server/transport/tcp/descriptor_limit.h"
#include "server/transport/tcp/tcp_session.h"

namespace sim4cv::transport {
namespace {

namespace asio = boost::asio;

class TcpTransport : public Transport {
 public:
  explicit TcpTransport(const TcpOptions& options) : options_(options), acceptor_(io_), accept_retry_(io_) {
    EnsureDescriptorsFor(options.max_clients);
    boost::system::error_code error;
    const auto address = asio::ip::make_address(options.bind_address, error);
    if (error) throw std::runtime_error("--bind '" + options.bind_address + "' is not an IP address: " + error.message());
    const asio::ip::tcp::endpoint endpoint(address, options.port);
    acceptor_.open(endpoint.protocol());
    acceptor_.set_option(asio::socket_base::reuse_address(true));
    acceptor_.bind(endpoint, error);
    if (error) {
      throw std::runtime_error("cannot listen on TCP " + options.bind_address + ":" + std::to_string(options.port) +
                               ": " + error.message() + " (pick another --tcp-port, or 0 for any free port)");
    }
    acceptor_.listen();
    port_ = acceptor_.local_endpoint().port();
  }

  ~TcpTransport() override { Stop(); }

  proto::TransportInfo info() const override {
    proto::TransportInfo info;
    info.set_kind(proto::TRANSPORT_KIND_TCP);
    info.set_address(std::to_string(port_));
    return info;
  }

  std::string listening_field() const override { return "tcp=" + std::to_string(port_); }

  void Start(const session::ServerContext& context) override {
    context_ = &context;
    Accept();
    thread_ = std::thread([this] { io_.run(); });
  }

  void Stop() override {
    if (!thread_.joinable()) return;
    asio::post(io_, [this] {
      boost::system::error_code ignored;
      acceptor_.close(ignored);
      accept_retry_.cancel();
      // Close() erases from sessions_ through the callback, so close copies.
      auto open = sessions_;
      for (auto& [id, session] : open) session->Close();
    });
    // Outstanding handlers finish (they see closed sockets), then run() returns.
    thread_.join();
  }

 private:
  void Accept() {
    acceptor_.async_accept([this](boost::system::error_code error, asio::ip::tcp::socket socket) {
      if (error == asio::error::operation_aborted || !acceptor_.is_open()) return;
      if (error) return AcceptFailed(error);
      const session::ClientId id = session::NewClientId();
      auto session = std::make_shared<TcpSession>(std::move(socket), id, *context_, options_,
                                                  [this](session::ClientId closed) { sessions_.erase(closed); });
      if (sessions_.size() >= options_.max_clients) {
        session->Reject(proto::ERROR_CODE_TOO_MANY_CLIENTS,
                        "the daemon already serves " + std::to_string(sessions_.size()) +
                            " clients (daemon flag --max-clients); try again after one disconnects");
      } else {
        sessions_.emplace(id, session);
        LOG_INFO("client " << id << " connected over TCP");
        session->Start();
      }
      Accept();
    });
  }

  // accept() failing again at once (out of descriptors: EMFILE, ENFILE; out
  // of memory) would spin the thread and flood the log, so wait
  // kAcceptRetryMs before the next try (connections wait in the kernel's
  // backlog meanwhile) and warn once per kAcceptErrorLogIntervalMs, with the count.
  void AcceptFailed(const boost::system::error_code& error) {
    using Clock = std::chrono::steady_clock;
    ++accept_failures_;
    const auto now = Clock::now();
    if (now >= next_accept_warning_) {
      LOG_WARNING("TCP accept failed " << accept_failures_ << " time(s) in the last "
                                       << limits::kAcceptErrorLogIntervalMs / 1000 << " s, last: " << error.message()
                                       << "; retrying every " << limits::kAcceptRetryMs << " ms ("
                                       << DescriptorUsage() << ")");
      accept_failures_ = 0;
      next_accept_warning_ = now + std::chrono::milliseconds(limits::kAcceptErrorLogIntervalMs);
    }
    accept_retry_.expires_after(std::chrono::milliseconds(limits::kAcceptRetryMs));
    accept_retry_.async_wait([this](boost::system::error_code wait_error) {
      if (!wait_error && acceptor_.is_open()) Accept();
    });
  }

  TcpOptions options_;
  asio::io_context io_;
  asio::ip::tcp::acceptor acceptor_;
  asio::steady_timer accept_retry_;
  uint64_t accept_failures_ = 0;
  std::chrono::steady_clock::time_point next_accept_warning_{};
  uint16_t port_ = 0;
  const session::ServerContext* context_ = nullptr;
  std::map<session::ClientId, std::shared_ptr<TcpSession>> sessions_;  // Asio thread only
  std::thread thread_;
};

}  // namespace

std::unique_ptr<Transport> MakeTcpTransport(const TcpOptions& options) { return std::make_unique<TcpTransport>(options); }

}  // namespace sim4cv::transport
