#include "server/session/access_token.h"

namespace sim4cv::session {
namespace {

// The value of `name` among `separator`-separated "name=value" items,
// ignoring spaces before a name.
std::string ItemValue(std::string_view items, std::string_view name, char separator) {
  while (!items.empty()) {
    const std::size_t end = items.find(separator);
    std::string_view item = items.substr(0, end);
    while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
    if (item.size() > name.size() && item.substr(0, name.size()) == name && item[name.size()] == '=') {
      return std::string(item.substr(name.size() + 1));
    }
    if (end == std::string_view::npos) break;
    items.remove_prefix(end + 1);
  }
  return {};
}

}  // namespace

bool TokenMatches(std::string_view given, std::string_view expected) {
  if (given.size() != expected.size()) return false;
  unsigned char difference = 0;
  for (std::size_t i = 0; i < given.size(); ++i) {
    difference |= static_cast<unsigned char>(given[i] ^ expected[i]);
  }
  return difference == 0;
}

std::string QueryValue(std::string_view query, std::string_view name) { return ItemValue(query, name, '&'); }

std::string CookieValue(std::string_view cookies, std::string_view name) { return ItemValue(cookies, name, ';'); }

}  // namespace sim4cv::session
