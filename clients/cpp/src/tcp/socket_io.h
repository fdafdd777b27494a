// POSIX socket primitives behind sim4cv::Client. Kept apart from the session
// logic so client.cpp reads as protocol, not as errno handling.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>

namespace sim4cv::detail {

using Deadline = std::chrono::steady_clock::time_point;

// Opens a blocking TCP socket to host:port with TCP_NODELAY (frames and Steps
// are latency-bound, Nagle would hold the small Step back). Tries every
// address `host` resolves to. Throws ConnectionError on failure or timeout.
int ConnectTcp(const std::string& host, uint16_t port, Deadline deadline);

enum class ReadStatus { kComplete, kTimeout };

// Reads into data[filled, size) until it is full or the deadline passes.
// `filled` advances with every byte, so a read cut by a timeout resumes where
// it stopped. Throws ConnectionError (naming `peer`) on EOF or socket errors.
ReadStatus ReadUntil(int fd, uint8_t* data, std::size_t size, std::size_t& filled, Deadline deadline,
                     const std::string& peer);

// Writes all `size` bytes, retrying partial writes and EINTR. Never raises
// SIGPIPE. Throws ConnectionError (naming `peer`) on failure.
void WriteAll(int fd, const void* data, std::size_t size, const std::string& peer);

}  // namespace sim4cv::detail
