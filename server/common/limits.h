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

// Default of --max-message-bytes: the largest Envelope a client may send. The
// largest legal request is a LoadMap carrying a map's text, which the map
// parser bounds at 1 MiB; 2 MiB holds that plus its Envelope with room to
// spare, and bounds what one message costs the TCP thread to read, hold and
// parse (issue 14, finding 11: 64 MiB messages stalled every TCP client).
// Frames the daemon sends are not bounded by it.
inline constexpr uint32_t kDefaultMaxMessageBytes = 2u << 20;
// TCP reads a message's body in pieces of at most this many bytes and grows
// its buffer only by what arrived: a length prefix alone allocates nothing
// (finding 4), and one handler never reads more than this for one client, so
// a large message is interleaved with every other client's traffic.
inline constexpr std::size_t kReadChunkBytes = 64u << 10;
// A connection's read and reply buffers larger than this are given back once
// their message is handled or sent: a burst's memory does not stay pinned.
inline constexpr std::size_t kKeptBufferBytes = 64u << 10;
// TCP back-pressure: while the replies waiting to be sent to one client (its
// own and the sim thread's) exceed this, the daemon reads nothing more from
// it, so a client that sends requests and never reads stops itself
// (finding 9) instead of growing the daemon. Not a hard cap: one more reply
// (at most a Welcome or a Configured with its WorldInfo) may be queued past it.
inline constexpr std::size_t kReplyBacklogBytes = 1u << 20;
// The sim thread's answers waiting for one client's transport thread
// (OfferedReplies, TCP and UDP). They come from requests already read, so
// only pipelined Configures and Controls the sim thread refuses fill it;
// past this the waiting answers are dropped and the client is closed with a
// fatal INVALID_STATE Error naming this limit.
inline constexpr std::size_t kMaxOfferedReplyBytes = 4u << 20;
// Defaults of --handshake-timeout-ms, --message-timeout-ms and
// --idle-timeout-ms (0: off). A silent or trickling connection holds one of
// --max-clients' slots; any real client says Hello and sends a whole message
// in milliseconds, so 10 s is generous. A handshaken client that is silent
// is a lockstep client paused in a debugger or a newest-frame reader that
// only reads: the idle timeout is off unless the operator asks for it.
inline constexpr uint32_t kDefaultHandshakeTimeoutMs = 10000;
inline constexpr uint32_t kDefaultMessageTimeoutMs = 10000;
inline constexpr uint32_t kDefaultIdleTimeoutMs = 0;
// After a fatal Error a connection closes once the Error is sent, or after
// this long if the client does not read it (its socket stays full).
inline constexpr uint32_t kCloseLingerMs = 2000;
// File descriptors the daemon keeps beyond one per --max-clients connection,
// for its own files and sockets (listening sockets, eventfds, epoll, the
// shared-memory object, a run log, a map being read) and for connections
// refused with TOO_MANY_CLIENTS while their Error goes out. The start is
// refused unless RLIMIT_NOFILE (raised towards its hard limit if needed)
// holds --max-clients plus these.
inline constexpr uint32_t kReservedDescriptors = 64;
// When accept() fails (e.g. out of descriptors, EMFILE), the TCP thread
// waits this long before trying again instead of spinning, and logs at
// most one warning per interval, with the count.
inline constexpr uint32_t kAcceptRetryMs = 100;
inline constexpr uint32_t kAcceptErrorLogIntervalMs = 10000;

// --- frames held for clients ---

// --- shared memory ---

}  // namespace sim4cv::limits
