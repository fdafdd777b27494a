// A listening TCP socket and its accept loop, shared by the TCP transport and
// the studio's HTTP port: bound where the flags say (errors name the flag),
// each accepted socket handed to the owner, and accept() failures (out of
// descriptors: EMFILE, ENFILE; out of memory) retried every
// limits::kAcceptRetryMs instead of spinning, with one warning per
// limits::kAcceptErrorLogIntervalMs that counts them. Asio thread only,
// after construction.
#pragma once

// clang-format off
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
// clang-format on
#include <boost/asio.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace sim4cv::transport {

class Listener {
 public:
  using OnSocket = std::function<void(boost::asio::ip::tcp::socket)>;

  // Binds and listens. `name` names the link in messages ("TCP", "HTTP");
  // `bind_flag`, `port_flag` the daemon flags that chose the address and
  // port. Throws std::runtime_error naming them.
  Listener(boost::asio::io_context& io, const std::string& bind_address, uint16_t port, const std::string& name,
           const std::string& bind_flag, const std::string& port_flag);

  uint16_t port() const { return port_; }
  bool loopback() const { return loopback_; }

  // Accepts until Close(), handing each socket to `on_socket`.
  void Start(OnSocket on_socket);
  void Close();

 private:
  void Accept();
  void AcceptFailed(const boost::system::error_code& error);

  boost::asio::ip::tcp::acceptor acceptor_;
  boost::asio::steady_timer retry_;
  std::string name_;
  OnSocket on_socket_;
  uint64_t failures_ = 0;
  std::chrono::steady_clock::time_point next_warning_{};
  uint16_t port_ = 0;
  bool loopback_ = true;
};

}  // namespace sim4cv::transport
