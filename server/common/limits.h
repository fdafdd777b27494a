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

// Names a client sends (Hello.client_name, Subscribe.camera, and every name in
// a Configure: entity, camera, route, map): they are logged, echoed in Errors
// and kept in the world, so a name is short. Over it: INVALID_ARGUMENT naming
// the field (fatal for Hello, which cannot be accepted without its name).
inline constexpr std::size_t kMaxNameBytes = 64;

// Client text quoted in an Error or a log line is cut to this many bytes
// (Quoted(), server/common/quoted.h), so an Error never grows with what the
// client sent.
inline constexpr std::size_t kQuotedBytes = 64;

// LoadMap.text: the largest map text the sim thread is asked to parse.
inline constexpr std::size_t kMaxMapTextBytes = std::size_t{4} << 20;

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

// LoadMap.traffic: agents the map's traffic steps every frame.
inline constexpr uint32_t kMaxTrafficCars = 500;
inline constexpr uint32_t kMaxTrafficParked = 2000;
inline constexpr uint32_t kMaxTrafficPedestrians = 2000;

// Configure requests one client has posted that the sim thread has not yet
// answered. The sim thread carries every posted request out before its next
// frame, so without this one client's pipelined LoadMaps stop every client's
// frames for seconds; with it, one client costs at most this many requests
// per frame. Over it: INVALID_STATE (not fatal) with the request's id.
inline constexpr uint32_t kMaxOutstandingConfigures = 4;

// --- frames held for clients ---

// --- shared memory ---

}  // namespace sim4cv::limits
