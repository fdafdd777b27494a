// Little-endian fixed-width fields in and out of byte buffers, for the run-log
// codec. Values are copied with memcpy, which is the file's byte order only on
// a little-endian host; the static_assert keeps a big-endian port honest.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>

namespace sim4cv::runlog::detail {

static_assert(std::endian::native == std::endian::little, "run logs are little-endian: add byte swaps here");

// Writes into a buffer the caller has sized exactly (see RecordPayloadSize),
// so no bounds checks are needed on the hot path.
class ByteWriter {
 public:
  explicit ByteWriter(uint8_t* out) : cursor_(out) {}

  template <typename T>
  void Put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    std::memcpy(cursor_, &value, sizeof value);
    cursor_ += sizeof value;
  }
  // u16 length, then the bytes (no terminator). The caller checks the length.
  void PutString(const std::string& text) {
    Put(static_cast<uint16_t>(text.size()));
    std::memcpy(cursor_, text.data(), text.size());
    cursor_ += text.size();
  }
  uint8_t* cursor() const { return cursor_; }

 private:
  uint8_t* cursor_;
};

// Reads with bounds checks: a damaged payload must fail, never read past its
// end. Every Get returns false once the bytes run out.
class ByteReader {
 public:
  explicit ByteReader(std::span<const uint8_t> bytes) : bytes_(bytes) {}

  template <typename T>
  bool Get(T* value) {
    static_assert(std::is_arithmetic_v<T>);
    if (remaining() < sizeof(T)) return false;
    std::memcpy(value, bytes_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return true;
  }
  bool GetString(std::string* text) {
    uint16_t size = 0;
    if (!Get(&size) || remaining() < size) return false;
    text->assign(reinterpret_cast<const char*>(bytes_.data() + offset_), size);
    offset_ += size;
    return true;
  }
  // A count of items of `item_bytes` each that must fit in what is left, so a
  // damaged count cannot make the decoder allocate gigabytes.
  bool GetCount(std::size_t item_bytes, uint32_t* count) {
    return Get(count) && static_cast<uint64_t>(*count) * item_bytes <= remaining();
  }
  std::size_t remaining() const { return bytes_.size() - offset_; }

 private:
  std::span<const uint8_t> bytes_;
  std::size_t offset_ = 0;
};

}  // namespace sim4cv::runlog::detail
