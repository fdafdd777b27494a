// The daemon's access token as a session sees it (docs/security.md): one
// secret per daemon, compared in constant time, found in Hello.token or,
// for the studio's WebSocket, in the cookie the page's ?token= URL set.
#pragma once

#include <string>
#include <string_view>

namespace sim4cv::session {

// The cookie the studio's token travels in.
inline constexpr std::string_view kTokenCookie = "sim4cv_token";

// Whether `given` is `expected`, in time that depends only on their
// lengths (a remote client cannot learn the token a byte at a time).
bool TokenMatches(std::string_view given, std::string_view expected);

// The value of `name` in a URL query ("a=1&token=x") or a Cookie header
// ("a=1; sim4cv_token=x"); empty if absent.
std::string QueryValue(std::string_view query, std::string_view name);
std::string CookieValue(std::string_view cookies, std::string_view name);

}  // namespace sim4cv::session
