#include "server/transport/tcp/tcp_transport.h"

#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
#include <boost/asio.hpp>
#include <map>
#include <thread>

#include "server/common/log.h"
#include "server/transport/tcp/tcp_session.h"

namespace sim4cv::transport {
namespace {

namespace asio = boost::asio;

class TcpTransport : public Transport {
 public:
  explicit TcpTransport(const TcpOptions& options) : options_(options), acceptor_(io_) {
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
      if (error) {
        if (error != asio::error::operation_aborted) LOG_WARNING("TCP accept failed: " << error.message());
        if (acceptor_.is_open() && error != asio::error::operation_aborted) Accept();
        return;
      }
      const session::ClientId id = session::NewClientId();
      auto session = std::make_shared<TcpSession>(std::move(socket), id, *context_, options_.send_buffer_bytes,
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

  TcpOptions options_;
  asio::io_context io_;
  asio::ip::tcp::acceptor acceptor_;
  uint16_t port_ = 0;
  const session::ServerContext* context_ = nullptr;
  std::map<session::ClientId, std::shared_ptr<TcpSession>> sessions_;  // Asio thread only
  std::thread thread_;
};

}  // namespace

std::unique_ptr<Transport> MakeTcpTransport(const TcpOptions& options) { return std::make_unique<TcpTransport>(options); }

}  // namespace sim4cv::transport
