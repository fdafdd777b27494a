#include "server/transport/tcp/listener.h"

#include <stdexcept>

#include "server/common/diagnostics.h"
#include "server/common/limits.h"
#include "server/transport/tcp/descriptor_limit.h"

namespace sim4cv::transport {

namespace asio = boost::asio;

Listener::Listener(asio::io_context& io, const std::string& bind_address, uint16_t port, const std::string& name,
                   const std::string& bind_flag, const std::string& port_flag)
    : acceptor_(io), retry_(io), name_(name) {
  boost::system::error_code error;
  const auto address = asio::ip::make_address(bind_address, error);
  if (error) throw std::runtime_error(bind_flag + " '" + bind_address + "' is not an IP address: " + error.message());
  const asio::ip::tcp::endpoint endpoint(address, port);
  acceptor_.open(endpoint.protocol());
  acceptor_.set_option(asio::socket_base::reuse_address(true));
  acceptor_.bind(endpoint, error);
  if (error) {
    throw std::runtime_error("cannot listen on " + name + " " + bind_address + ":" + std::to_string(port) + ": " +
                             error.message() + " (pick another " + port_flag + ", or 0 for any free port)");
  }
  acceptor_.listen();
  port_ = acceptor_.local_endpoint().port();
  loopback_ = address.is_loopback();
}

void Listener::Start(OnSocket on_socket) {
  on_socket_ = std::move(on_socket);
  Accept();
}

void Listener::Close() {
  boost::system::error_code ignored;
  acceptor_.close(ignored);
  retry_.cancel();
}

void Listener::Accept() {
  acceptor_.async_accept([this](boost::system::error_code error, asio::ip::tcp::socket socket) {
    if (error == asio::error::operation_aborted || !acceptor_.is_open()) return;
    if (error) return AcceptFailed(error);
    on_socket_(std::move(socket));
    Accept();
  });
}

// accept() failing again at once would spin the thread and flood the log, so
// wait (connections wait in the kernel's backlog meanwhile) and warn once per
// interval, with the count.
void Listener::AcceptFailed(const boost::system::error_code& error) {
  ++failures_;
  const auto now = std::chrono::steady_clock::now();
  if (now >= next_warning_) {
    LOG_WARNING(name_ << " accept failed " << failures_ << " time(s) in the last "
                      << limits::kAcceptErrorLogIntervalMs / 1000 << " s, last: " << error.message()
                      << "; retrying every " << limits::kAcceptRetryMs << " ms (" << DescriptorUsage() << ")");
    failures_ = 0;
    next_warning_ = now + std::chrono::milliseconds(limits::kAcceptErrorLogIntervalMs);
  }
  retry_.expires_after(std::chrono::milliseconds(limits::kAcceptRetryMs));
  retry_.async_wait([this](boost::system::error_code wait_error) {
    if (!wait_error && acceptor_.is_open()) Accept();
  });
}

}  // namespace sim4cv::transport
