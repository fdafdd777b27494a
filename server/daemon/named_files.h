// The files clients reach by name: maps under --maps-dir (LoadMap.name,
// ListMaps, the studio's OpenMap / SaveMap) and run logs under --logs-dir
// (StartLog). Every path is confined to its folder: a name is checked part
// by part on the network thread (configure_check), and here no symbolic link
// is followed out of it. Runs on the sim thread, between frames, like
// LoadMap's own file.
#pragma once

#include <google/protobuf/repeated_ptr_field.h>

#include <string>

namespace sim4cv::daemon {

// Appends to `names` the path of every regular "*.map" file under `maps_dir`
// (recursively, symbolic links not followed), relative to it and without
// ".map", e.g. "tracking/easy_urban"; sorted, at most limits::kMaxListedMaps.
// A missing or unreadable folder lists nothing.
void ListMapNames(const std::string& maps_dir, google::protobuf::RepeatedPtrField<std::string>& names);

// The bytes of "<maps_dir>/<name>.map". Throws ConfigureError: INVALID_ARGUMENT
// for a missing map or a symbolic link on the way, IO when it cannot be read
// or is larger than limits::kMaxMapTextBytes.
std::string ReadMapFile(const std::string& maps_dir, const std::string& name);

// Writes `text` to "<maps_dir>/<name>.map" (missing folders created): to a
// temporary file beside it, flushed, then renamed over it, so a reader or a
// crash sees the old map or the new one, never half of one. Throws
// ConfigureError: ALREADY_EXISTS when the file exists and !overwrite,
// INVALID_ARGUMENT for a symbolic link or a non-folder on the way, IO when
// the system refuses (the message names the path and the reason).
void WriteMapFile(const std::string& maps_dir, const std::string& name, const std::string& text, bool overwrite);

// The path of a new run log "<logs_dir>/<name>.s4log" (missing folders
// created), for runlog::RunLogWriter to create. Throws ConfigureError:
// INVALID_STATE without --logs-dir, ALREADY_EXISTS when the file exists and
// !overwrite, INVALID_ARGUMENT for a symbolic link or a non-folder on the
// way, IO when a folder cannot be made.
std::string NewLogPath(const std::string& logs_dir, const std::string& name, bool overwrite);

}  // namespace sim4cv::daemon
