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

}  // namespace sim4cv::limits
