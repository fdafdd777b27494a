// CRC-32 (IEEE 802.3, the polynomial of zlib, PNG and gzip): guards each
// run-log record, so a torn or damaged record is told apart from a good one.
// Our own ~20 lines rather than a zlib dependency; crc32("123456789") is
// 0xCBF43926, as in every other implementation.
#pragma once

#include <cstdint>
#include <span>

namespace sim4cv::runlog {

// The CRC of `data`. Chain calls by passing the previous result as `crc`.
uint32_t Crc32(std::span<const uint8_t> data, uint32_t crc = 0);

}  // namespace sim4cv::runlog
