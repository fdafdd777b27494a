// Client text (a name, a map line) inside an Error or a log line: quoted, cut
// to a few bytes and with control characters escaped, so neither grows with
// what a client sent nor lets it forge log lines.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <string_view>

#include "server/common/limits.h"

namespace sim4cv {

// 'abc' when `text` fits in `max_bytes`; else 'abc…' (N bytes) with N the
// whole text's size. Never cuts a UTF-8 sequence in two: an Error's message
// is a proto3 string, which a client refuses to parse unless it is valid UTF-8.
inline std::string Quoted(std::string_view text, std::size_t max_bytes = limits::kQuotedBytes) {
  std::size_t cut = std::min(text.size(), max_bytes);
  if (cut < text.size()) {
    while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;  // a continuation byte
  }
  std::string out;
  out.reserve(cut + 24);
  out += '\'';
  for (std::size_t i = 0; i < cut; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c != 0x7F) {
      out += static_cast<char>(c);
      continue;
    }
    static constexpr char kHex[] = "0123456789abcdef";
    out += "\\x";
    out += kHex[c >> 4];
    out += kHex[c & 0xF];
  }
  if (cut < text.size()) out += "\xE2\x80\xA6";  // …
  out += '\'';
  if (cut < text.size()) out += " (" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace sim4cv
