// One HTTP connection of the studio's port, until it asks to become a
// WebSocket: reads requests (bounded headers, no bodies, timed), answers GET
// and HEAD from the page's files and /clock, and hands an upgrade to "/ws"
// to a WsSession. Over --http-max-clients it answers 503, or the WebSocket's
// TOO_MANY_CLIENTS Error, and closes.
#pragma once

// clang-format off
#include <utility>  // Boost 1.74 Asio uses std::exchange without including it
// clang-format on

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <memory>
#include <optional>
#include <string>

#include "server/transport/http/http_hub.h"
#include "server/transport/http/ws_frame_writer.h"

namespace sim4cv::transport {

class HttpConnection : public HttpPeer, public std::enable_shared_from_this<HttpConnection> {
 public:
  // `over_capacity`: answer the first request with a refusal, then close.
  HttpConnection(boost::asio::ip::tcp::socket socket, uint64_t key, HttpHub& hub, bool over_capacity);

  void Start();
  void Close() override;
  bool half_open() const override { return !answered_; }

  // "" if a WebSocket upgrade from a page at `origin` (empty: not a browser)
  // to `host` may proceed, else why not: a page of another site (cross-site
  // WebSocket hijacking), or a Host that is not an IP address or localhost
  // (DNS rebinding). Public for its unit test.
  static std::string CheckOrigin(const std::string& origin, const std::string& host);
  // The view options of a WebSocket URL's query ("rgb=raw&quality=90"), or
  // nullopt and `problem`.
  static std::optional<WsViewOptions> ParseViewQuery(const std::string& query, std::string& problem);

 private:
  using Request = boost::beast::http::request<boost::beast::http::empty_body>;

  void ReadRequest();
  void OnRequest(const boost::system::error_code& error);
  void Upgrade(Request request);
  void Respond(boost::beast::http::status status, std::string body, const std::string& content_type, bool keep_alive);

  boost::beast::tcp_stream stream_;
  uint64_t key_;
  HttpHub& hub_;
  bool over_capacity_;
  boost::beast::flat_buffer buffer_;
  std::optional<boost::beast::http::request_parser<boost::beast::http::empty_body>> parser_;
  boost::beast::http::response<boost::beast::http::string_body> response_;
  bool closed_ = false;
  bool handed_over_ = false;  // the socket is a WsSession's now
  bool answered_ = false;     // a whole request arrived (half_open until then)
  std::string set_cookie_;    // the studio's token cookie, sent with the next response
  unsigned response_version_ = 11;  // the request's HTTP version: 10 or 11
};

}  // namespace sim4cv::transport
