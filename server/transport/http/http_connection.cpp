#include "server/transport/http/http_connection.h"

#include <time.h>

#include <boost/beast/websocket.hpp>
#include <charconv>
#include <utility>

#include "server/common/diagnostics.h"
#include "server/common/limits.h"
#include "server/common/quoted.h"
#include "server/session/access_token.h"
#include "server/transport/http/ws_session.h"

namespace sim4cv::transport {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;

namespace {

// CLOCK_MONOTONIC in nanoseconds: the clock of Frame.render_end_mono_ns, so a
// page can estimate its offset and show a frame's latency.
int64_t MonotonicNs() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<int64_t>(now.tv_sec) * 1000000000 + now.tv_nsec;
}

bool IsIpLiteralOrLocalhost(std::string host) {
  if (host.empty()) return false;
  if (host.front() == '[') return host.find(']') != std::string::npos;  // [::1]:port
  host = host.substr(0, host.rfind(':') == std::string::npos ? host.size() : host.rfind(':'));
  if (host == "localhost") return true;
  boost::system::error_code error;
  asio::ip::make_address_v4(host, error);
  return !error;
}

}  // namespace

std::string HttpConnection::CheckOrigin(const std::string& origin, const std::string& host) {
  if (!IsIpLiteralOrLocalhost(host)) {
    return "the WebSocket was asked for host " + Quoted(host) +
           "; open the studio by IP address or localhost (a host name could be rebound to this daemon by another "
           "site)";
  }
  if (!origin.empty() && origin != "http://" + host) {
    return "a page from " + Quoted(origin) +
           " may not open the studio's WebSocket; only the studio's own page (http://" + host + ") may";
  }
  return {};
}

std::optional<WsViewOptions> HttpConnection::ParseViewQuery(const std::string& query, std::string& problem) {
  WsViewOptions view;
  for (std::size_t start = 0; start < query.size();) {
    std::size_t end = query.find('&', start);
    if (end == std::string::npos) end = query.size();
    const std::string item = query.substr(start, end - start);
    start = end + 1;
    if (item.empty()) continue;
    const std::size_t equals = item.find('=');
    const std::string key = item.substr(0, equals);
    const std::string value = equals == std::string::npos ? "" : item.substr(equals + 1);
    if (key == "rgb" && (value == "jpeg" || value == "raw")) {
      view.jpeg_rgb = value == "jpeg";
    } else if (key == "quality") {
      int quality = 0;
      const auto [end_of_number, error] = std::from_chars(value.data(), value.data() + value.size(), quality);
      if (error != std::errc() || end_of_number != value.data() + value.size() || quality < 1 || quality > 100) {
        problem = "quality=" + Quoted(value) + ": give a JPEG quality from 1 to 100";
        return std::nullopt;
      }
      view.jpeg_quality = quality;
    } else {
      problem = Quoted(item) + " is not a WebSocket option; use rgb=jpeg or rgb=raw, and quality=1..100";
      return std::nullopt;
    }
  }
  return view;
}

HttpConnection::HttpConnection(asio::ip::tcp::socket socket, uint64_t key, HttpHub& hub, bool over_capacity)
    : stream_(std::move(socket)), key_(key), hub_(hub), over_capacity_(over_capacity) {}

void HttpConnection::Start() { ReadRequest(); }

void HttpConnection::ReadRequest() {
  parser_.emplace();
  parser_->header_limit(limits::kMaxHttpHeaderBytes);
  parser_->body_limit(0);  // the studio's requests have no body
  const uint32_t timeout_ms = hub_.options.timeouts.handshake_ms;
  if (timeout_ms == 0) {
    stream_.expires_never();
  } else {
    stream_.expires_after(std::chrono::milliseconds(over_capacity_ ? std::min(timeout_ms, 1000u) : timeout_ms));
  }
  http::async_read(
      stream_, buffer_, *parser_,
      [self = shared_from_this()](boost::system::error_code error, std::size_t) { self->OnRequest(error); });
}

void HttpConnection::OnRequest(const boost::system::error_code& error) {
  if (closed_) return;
  if (error == http::error::end_of_stream || error == beast::error::timeout || error == asio::error::eof ||
      error == asio::error::connection_reset) {
    return Close();  // gone, or silent past the deadline: nothing to answer
  }
  if (error == http::error::header_limit) {
    return Respond(http::status::request_header_fields_too_large,
                   "request headers over " + std::to_string(limits::kMaxHttpHeaderBytes) + " bytes\n", "text/plain",
                   false);
  }
  if (error)
    return Respond(http::status::bad_request, "bad HTTP request: " + error.message() + "\n", "text/plain", false);

  answered_ = true;
  Request request = parser_->release();
  // Answered in the request's version, so an HTTP/1.0 client that asked to
  // keep the connection is told it was kept (Connection: keep-alive).
  response_version_ = request.version() == 10 ? 10 : 11;
  const std::string target(request.target());
  const std::string path = target.substr(0, target.find('?'));
  if (over_capacity_) {
    const std::string why = "the daemon already serves " + std::to_string(hub_.options.max_clients) +
                            " HTTP connections (daemon flag --http-max-clients); close a studio tab and reload";
    if (beast::websocket::is_upgrade(request) && path == "/ws") {
      handed_over_ = true;
      auto session = std::make_shared<WsSession>(std::move(stream_), key_, hub_, WsViewOptions{});
      hub_.Register(key_, session, true);
      return session->Reject(std::move(request), proto::ERROR_CODE_TOO_MANY_CLIENTS, why);
    }
    return Respond(http::status::service_unavailable, why + "\n", "text/plain", false);
  }
  if (beast::websocket::is_upgrade(request)) return Upgrade(std::move(request));
  if (request.method() != http::verb::get && request.method() != http::verb::head) {
    return Respond(http::status::method_not_allowed, "the studio answers GET and HEAD only\n", "text/plain", false);
  }
  const bool keep_alive = request.keep_alive();
  if (path == "/clock") {
    return Respond(http::status::ok, std::to_string(MonotonicNs()), "text/plain", keep_alive);
  }
  // The studio opened as http://HOST:PORT/?token=T: the page's WebSockets
  // carry T in a cookie from then on (docs/security.md).
  const std::string& token = hub_.context->access_token;
  const std::string given = session::QueryValue(target.substr(path.size() + (path.size() < target.size())), "token");
  if (!token.empty() && !given.empty() && session::TokenMatches(given, token)) {
    set_cookie_ = std::string(session::kTokenCookie) + "=" + given + "; Path=/; HttpOnly; SameSite=Strict";
  }
  const StaticFiles::File* file = hub_.files.Find(path);
  if (file == nullptr) {
    return Respond(http::status::not_found, "no such studio file: " + Quoted(path) + "\n", "text/plain", keep_alive);
  }
  Respond(http::status::ok, request.method() == http::verb::head ? std::string() : file->bytes, file->content_type,
          keep_alive);
}

void HttpConnection::Upgrade(Request request) {
  const std::string target(request.target());
  const std::size_t question = target.find('?');
  if (target.substr(0, question) != "/ws") {
    return Respond(http::status::not_found, "the studio's WebSocket is at /ws\n", "text/plain", false);
  }
  const std::string refused =
      CheckOrigin(std::string(request[http::field::origin]), std::string(request[http::field::host]));
  if (!refused.empty()) {
    LOG_INFO("refused a WebSocket: " << refused);
    return Respond(http::status::forbidden, refused + "\n", "text/plain", false);
  }
  std::string problem;
  const auto view = ParseViewQuery(question == std::string::npos ? "" : target.substr(question + 1), problem);
  if (!view) return Respond(http::status::bad_request, problem + "\n", "text/plain", false);
  // The cookie the page's ?token= URL set stands for Hello.token.
  const std::string& token = hub_.context->access_token;
  const bool authenticated =
      !token.empty() && session::TokenMatches(session::CookieValue(std::string(request[http::field::cookie]), session::kTokenCookie), token);
  handed_over_ = true;
  auto session = std::make_shared<WsSession>(std::move(stream_), key_, hub_, *view);
  hub_.Register(key_, session, false);  // replaces this connection, which goes when its handler returns
  session->Start(std::move(request), authenticated);
}

void HttpConnection::Respond(http::status status, std::string body, const std::string& content_type, bool keep_alive) {
  keep_alive = keep_alive && !over_capacity_;
  response_ = {};
  response_.result(status);
  response_.version(response_version_);
  response_.set(http::field::server, "sim4cvd");
  response_.set(http::field::content_type, content_type);
  response_.set(http::field::cache_control, "no-store");  // a restarted daemon's page must not be stale
  response_.set("X-Content-Type-Options", "nosniff");
  if (!set_cookie_.empty()) response_.set(http::field::set_cookie, std::exchange(set_cookie_, {}));
  // Script only from the studio's own files: a name a client gave an entity
  // can never run as inline script or an event handler in the page.
  response_.set("Content-Security-Policy",
                "default-src 'self'; script-src 'self'; object-src 'none'; base-uri 'none'; "
                "frame-ancestors 'none'; form-action 'none'; img-src 'self' data: blob:; "
                "style-src 'self' 'unsafe-inline'");
  response_.keep_alive(keep_alive);
  response_.body() = std::move(body);
  response_.prepare_payload();
  http::async_write(stream_, response_,
                    [self = shared_from_this(), keep_alive](boost::system::error_code error, std::size_t) {
                      if (self->closed_) return;
                      if (error || !keep_alive) return self->Close();
                      self->ReadRequest();
                    });
}

void HttpConnection::Close() {
  // Once handed over, the socket and the hub's entry under key_ are the WsSession's.
  if (closed_ || handed_over_) return;
  closed_ = true;
  boost::system::error_code ignored;
  stream_.socket().shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
  stream_.socket().close(ignored);
  hub_.Forget(key_);
}

}  // namespace sim4cv::transport
