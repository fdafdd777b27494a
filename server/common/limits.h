// Every bound on what outside input may make the daemon allocate or loop
// over, in one place (docs/protocol.md, "Limits"; docs/reliability.md has the
// memory budget they add up to). Input over a limit gets an Error naming the
// limit (and its flag, where it has one); nothing here is checked per frame.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sim4cv::limits {

// --- maps and run logs (values read from files are checked as strictly as the network's) ---

// A map (--map, LoadMap by name or text) is parsed into a Map, a RoadGraph,
// meshes and, on urban maps or with traffic, a TrafficPlan, all on the sim
// thread while every client's frames wait; their cost grows with what these
// bound. The worst map they accept (docs/maps.md, "Limits": 16x16
// crossroads of 50 m in a 40x40 grid, 2000 objects, 64 routes, urban, with
// traffic) loads in 3.6 s of CPU and 141 MB peak RSS; a shipped map in
// 0.2 s and 81 MB. Shipped maps are at most 12x12 tiles of 20 m or 5x4 of
// 50 m, 68 road tiles, 189 objects. A map over one is refused by the
// parser, naming the line and the limit.

// tile_size, metres (the lower bound, 12 m, is map::kMinTileSize: the car's
// turning circle). Lanes, crosswalks and their meshes are sampled along a
// tile, so its cost grows with it; a huge tile once sized the ground mesh
// into bad_alloc (docs/reliability.md, finding 1).
inline constexpr double kMaxMapTileSize = 50.0;
// grid W H: tiles each way (the extent below at the smallest tile, 12 m).
inline constexpr int kMaxMapGridSide = 166;
// The world a map covers, metres each way (W * tile_size and H *
// tile_size): the ground mesh has a vertex every 10 m of it, and it stays
// inside the 2 km ground skirt (cameras see 1 km).
inline constexpr double kMaxMapExtentMetres = 2000.0;
// Road tiles ('#' or a mask): each is up to 12 lane segments, a road mesh
// and, on urban maps, a junction's lights, crosswalks and their lane
// crossings (about 10 ms of CPU per crossroads). A 300x300 all-road grid
// (90,000 road tiles) took 16 s and 2.9 GB (docs/reliability.md, finding 2).
inline constexpr int kMaxMapRoadTiles = 256;
// 'object' lines: each is a labelled object with its own mesh, drawn by
// every camera every frame, and checked by the traffic's layout.
inline constexpr int kMaxMapObjects = 2000;
// Object coordinates, metres from the origin, each axis (as far again as
// the largest grid reaches), and rotations, degrees: one turn either way.
inline constexpr double kMaxMapObjectCoordinate = kMaxMapExtentMetres;
inline constexpr double kMaxMapObjectRotationDeg = 360.0;
// 'route' lines, and tiles per route (a closed route may pass a junction
// more than once, so a route may list more tiles than the map has).
inline constexpr int kMaxMapRoutes = 64;
inline constexpr int kMaxMapRouteTiles = 4 * kMaxMapRoadTiles;

// Poses read from a run log for --replay: every coordinate of a position,
// linear and angular velocity must be finite and within this, the bound a
// client's coordinates have (CheckConfigure's "finite": |v| <= 1e6), and an
// orientation a unit quaternion within kLogQuaternionNormTolerance;
// anything else (a run whose physics blew up) would reach the renderer's
// camera maths on the first replayed frame (docs/reliability.md, finding 3). Refused at start.
inline constexpr double kMaxWorldCoordinate = 1e6;
inline constexpr double kLogQuaternionNormTolerance = 1e-3;

// --- messages, names and per-client queues ---

// Names a client sends (Hello.client_name, Subscribe.camera, and every name in
// a Configure: entity, camera, route, map): they are logged, echoed in Errors
// and kept in the world, so a name is short. Over it: INVALID_ARGUMENT naming
// the field (fatal for Hello, which cannot be accepted without its name).
inline constexpr std::size_t kMaxNameBytes = 64;

// Client text quoted in an Error or a log line is cut to this many bytes
// (Quoted(), server/common/quoted.h), so an Error never grows with what the
// client sent.
inline constexpr std::size_t kQuotedBytes = 64;

// LoadMap.text (and a --map file): the largest map text the sim thread is
// asked to parse. Shipped maps are under 8 KB; 1 MiB leaves room for maps far
// larger than any the map-size limits below accept.
inline constexpr std::size_t kMaxMapTextBytes = std::size_t{1} << 20;

// One line of a map (LoadMap.text or a --map file): every parser Error
// quotes tokens of its line, so the line is bounded, well above a grid row
// of the widest grid.
inline constexpr std::size_t kMaxMapLineBytes = 4096;

// SetRoute.waypoints.points: each point is kept (and checked) by the car's
// route follower.
inline constexpr int kMaxRouteWaypoints = 100000;

// QueryRoad.count: lane points computed and sent back per query.
inline constexpr uint32_t kMaxRoadQueryPoints = 100;

// AddCamera.width/height: an added camera's image, rendered every frame and
// held per subscriber (the scene's own cameras follow --width/--height).
inline constexpr uint32_t kMaxAddedCameraWidth = 1920;
inline constexpr uint32_t kMaxAddedCameraHeight = 1080;

// Cameras at once (AddCamera over it: INVALID_STATE): every frame renders
// each subscribed one. Removed cameras keep their index (a subscription by
// index is never handed another camera) until LoadMap or Reset, so the
// indices used since are bounded too.
inline constexpr std::size_t kMaxCameras = 32;
inline constexpr std::size_t kMaxCameraIndices = 1024;

// LoadMap.traffic: entities the map's traffic steps every frame.
inline constexpr uint32_t kMaxTrafficCars = 500;
inline constexpr uint32_t kMaxTrafficParked = 2000;
inline constexpr uint32_t kMaxTrafficPedestrians = 2000;

// Configure requests one client has posted that the sim thread has not yet
// answered. The sim thread carries every posted request out before its next
// frame, so without this one client's pipelined LoadMaps stop every client's
// frames for seconds; with it, one client costs at most this many requests
// per frame. Over it: INVALID_STATE (not fatal) with the request's id.
inline constexpr uint32_t kMaxOutstandingConfigures = 4;

// The sim thread's time for Configures between two frames: once the
// Configures it carried out since it last drained the queue took this long,
// the rest (and every command after them, so the order holds) waits until
// after the next frame. Authoring requests (CheckMap, GenerateMap, SaveMap,
// OpenMap, ListMaps) do not count: a worker thread answers them.
inline constexpr uint32_t kConfigureBudgetPerFrameMs = 10;

// Default of --max-message-bytes: the largest Envelope a client may send. The
// largest legal request is a LoadMap carrying a map's text (at most
// kMaxMapTextBytes); another MiB holds its Envelope with room to spare, and bounds what one message costs the TCP
// thread to read, hold and parse (docs/reliability.md, finding 11: 64 MiB messages stalled every TCP client). Frames the daemon
// sends are not bounded by it.
inline constexpr uint32_t kDefaultMaxMessageBytes = static_cast<uint32_t>(kMaxMapTextBytes) + (1u << 20);
// TCP reads a message's body in pieces of at most this many bytes and grows
// its buffer only by what arrived: a length prefix alone allocates nothing
// (docs/reliability.md, finding 4), and one handler never reads more than this for one client, so
// a large message is interleaved with every other client's traffic.
inline constexpr std::size_t kReadChunkBytes = 64u << 10;
// A connection's read and reply buffers larger than this are given back once
// their message is handled or sent: a burst's memory does not stay pinned.
inline constexpr std::size_t kKeptBufferBytes = 64u << 10;
// TCP back-pressure: while the replies waiting to be sent to one client (its
// own and the sim thread's) exceed this, the daemon reads nothing more from
// it, so a client that sends requests and never reads stops itself
// (docs/reliability.md, finding 9) instead of growing the daemon. Not a hard cap: one more reply
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
// Commands from every client waiting for the sim thread. Steps, Configures
// and Subscribes are bounded per client above (and by their replies), but
// Controls and TrackerOutputs need no answer: a client can send millions a
// second, and while the sim thread is busy (a LoadMap) they would pile up.
// Past this, they are dropped with a non-fatal INVALID_STATE Error (whose
// replies then hold the sender back, kReplyBacklogBytes). About 200 bytes
// each: 16384 hold ~3 MiB.
inline constexpr std::size_t kMaxQueuedCommands = 16384;

// --- frames held for clients ---

// Steps a lockstep client may send ahead of the frames it has received; one
// more is refused (INVALID_STATE, not fatal). Steps are counters, so this
// bounds no memory by itself: kLockstepFramesQueued does.
inline constexpr std::size_t kMaxOutstandingSteps = 64;

// Rendered frames waiting in one lockstep client's mailbox (besides the one
// its transport is sending). While the mailbox is full the client is not
// ready, so a lockstep simulation waits for it to read, as it waits for its
// Steps: a client that Steps 64 times and never reads holds at most
// kLockstepFramesQueued + 1 frames (at 1920x1080, 19 MB each with RGB, depth
// and mask, 62 MB with all six pixel channels), not 64. Two keep a pipelining client's next frame rendered while it
// reads the last one.
inline constexpr std::size_t kLockstepFramesQueued = 2;

// The frame pool gives back what a burst left behind: once a second
// (kFramePoolTrimPeriodMs) the sim thread frees the free frames beyond the
// most that were in use since the last trim, plus kFramePoolSpare. Frames in
// steady use are never freed, so steady state allocates nothing.
inline constexpr std::size_t kFramePoolSpare = 2;
inline constexpr int64_t kFramePoolTrimPeriodMs = 1000;

// ListMaps: map names one answer lists (Configured.maps), so a --maps-dir
// holding a huge tree cannot make one answer huge; the shipped maps are 44.
inline constexpr std::size_t kMaxListedMaps = 1000;

// A map's or run log's name (OpenMap, SaveMap, StartLog): each '/'-separated
// part at most this long, so the file's name with ".map" or ".s4log", and
// SaveMap's temporary ".NAME.map.tmpPID" beside it, stay within the file
// system's 255 bytes; a longer part is refused before any folder is made.
inline constexpr std::size_t kMaxFileNamePartBytes = 200;
// ListMaps: how deep below --maps-dir the walk goes.
inline constexpr int kMaxListedMapDepth = 8;
// SaveMap's quota per folder under --maps-dir: at most this many ".map"
// files and bytes of them (the new map counted, the one it replaces not), so
// one client cannot fill the disk (255 MB in 1.5 s before). Over it:
// IO, naming the folder and the limit.
inline constexpr std::size_t kMaxMapsPerFolder = 1000;
inline constexpr std::uint64_t kMaxMapFolderBytes = std::uint64_t{64} << 20;

// Subscribe.max_fps: the highest frame rate cap a subscriber may ask for
// (above it, ask for 0: every frame).
inline constexpr double kMaxSubscribeFps = 1000.0;

// --- the studio's HTTP port (--http-port; docs/studio.md) ---
// An HTTP request's start line and headers (a browser's are under 2 KiB);
// over it the connection is answered 431 and closed.
inline constexpr uint32_t kMaxHttpHeaderBytes = 16u << 10;
// Connections over --http-max-clients are answered (HTTP 503, or a
// WebSocket's TOO_MANY_CLIENTS Error) and closed; while this many such
// answers are under way, further ones are closed at once unanswered, so a
// flood of connections holds a bounded number of descriptors.
inline constexpr uint32_t kMaxHttpRejecting = 16;
// A WebSocket client's keep-alive: the daemon pings a connection silent for
// half of this and closes it when nothing, not even the pong, came back in
// it. A page that stops reading stops answering behind its unread frames.
inline constexpr uint32_t kWebSocketIdleTimeoutMs = 30000;

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
