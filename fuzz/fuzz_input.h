// Input formats the fuzz targets share. Targets whose decoder takes one
// message at a time (a UDP datagram) read their input as records: a 2-byte
// little-endian length, then that many bytes; a last record shorter than its
// length takes what is left. sim4cv_fuzz_seeds writes seeds in this format.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/diagnostics.h"

namespace sim4cv::fuzz {

inline std::vector<std::string_view> SplitRecords(const uint8_t* data, std::size_t size) {
  std::vector<std::string_view> records;
  std::size_t at = 0;
  while (at + 2 <= size) {
    const std::size_t length = data[at] | (std::size_t{data[at + 1]} << 8);
    at += 2;
    const std::size_t take = length < size - at ? length : size - at;
    records.emplace_back(reinterpret_cast<const char*>(data + at), take);
    at += take;
  }
  return records;
}

inline void AppendRecord(std::string& out, std::string_view record) {
  out.push_back(static_cast<char>(record.size() & 0xff));
  out.push_back(static_cast<char>((record.size() >> 8) & 0xff));
  out.append(record);
}

// Client misbehaviour is logged at INFO, once per refused input: at fuzzing
// rates that is only noise. Warnings and errors still show.
inline void QuietLogs() { diagnostics::SetMinLevel(diagnostics::Level::kWarning); }

}  // namespace sim4cv::fuzz
