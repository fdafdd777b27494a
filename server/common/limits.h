// Every bound on what outside input may make the daemon allocate or loop
// over, in one place (docs/protocol.md, "Limits"; docs/reliability.md has the
// memory budget they add up to). Input over a limit gets an Error naming the
// limit (and its flag, where it has one); nothing here is checked per frame.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sim4cv::limits {

// --- maps and run logs (values read from files are checked as strictly as the network's) ---

// --- messages, names and per-client queues ---

// --- frames held for clients ---

// --- shared memory ---
// The request ring, response ring and message sizes of a client's area are
// layout constants (protocol/shm_layout.h: kShmRequestCapacity 64 requests of
// at most kShmRequestDataBytes 248 bytes, kShmResponseDepth 8 responses of at
// most 1984 bytes), the same for every daemon of a layout version.

// Shared-memory clients attached at once; more are refused with the reason
// (counter shm.refused). Each holds a 36 KiB area, a socket and an eventfd in
// the daemon: 64 of them are 2.3 MiB and 128 descriptors.
inline constexpr uint32_t kShmMaxClients = 64;
// Requests the shm thread takes from one client before it serves the next:
// one ring's worth, so a client that floods its ring delays no one else.
inline constexpr uint32_t kShmRequestsPerTurn = 64;
// After accept() fails for lack of descriptors, the shm listener rests this
// long instead of waking its thread again at once for the same connection.
inline constexpr uint32_t kShmAcceptRestMs = 100;

}  // namespace sim4cv::limits
