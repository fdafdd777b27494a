// The files clients reach by name: maps under --maps-dir (LoadMap.name,
// ListMaps, the studio's OpenMap / SaveMap) and run logs under --logs-dir
// (StartLog). Every path is confined to its folder: a name is checked part
// by part on the network thread (configure_check), and here every file is
// opened from the folder's descriptor with no symbolic link followed in any
// part at the moment of opening (server/common/beneath.h), so a link
// swapped in after a check is never followed.
#pragma once

#include <google/protobuf/repeated_ptr_field.h>

#include <string>

#include "server/common/beneath.h"

namespace sim4cv::daemon {

// Appends to `names` the path of every regular "*.map" file under `maps_dir`
// (recursively, symbolic links not followed), relative to it and without
// ".map", e.g. "tracking/easy_urban"; sorted, at most limits::kMaxListedMaps.
// A missing or unreadable folder lists nothing.
void ListMapNames(const std::string& maps_dir, google::protobuf::RepeatedPtrField<std::string>& names);

// The bytes of "<maps_dir>/<name>.map". Throws ConfigureError naming
// `field` ("OpenMap.name", "LoadMap.name"): INVALID_ARGUMENT for a missing
// map, a symbolic link on the way or a file that is not regular, IO when it
// cannot be read or is larger than limits::kMaxMapTextBytes. Never quotes
// the file's content.
std::string ReadMapFile(const std::string& maps_dir, const std::string& name, const char* field);

// Writes `text` to "<maps_dir>/<name>.map" (missing folders created): to a
// temporary file beside it, flushed, then renamed over it, so a reader or a
// crash sees the old map or the new one, never half of one. Throws
// ConfigureError: ALREADY_EXISTS when the file exists and !overwrite,
// INVALID_ARGUMENT for a symbolic link or a non-folder on the way, IO when
// the system refuses (the message names the path and the reason).
void WriteMapFile(const std::string& maps_dir, const std::string& name, const std::string& text, bool overwrite);

// A run log just created beneath --logs-dir, open for writing.
struct NewLogFile {
  Fd fd;
  std::string path;  // for messages and WorldInfo.log_file
  Fd folder;         // the log's folder, to remove it by name (Discard)
  std::string leaf;  // "NAME.s4log"
  // Removes the file (a StartLog that failed after creating it).
  void Discard();
};

// Creates "<logs_dir>/<name>.s4log" (missing folders created); with
// `overwrite` an existing log is removed first (never truncated through a
// link). Throws ConfigureError: INVALID_STATE without --logs-dir,
// ALREADY_EXISTS when the file exists and !overwrite, INVALID_ARGUMENT for
// a symbolic link or a non-folder on the way, IO when the system refuses.
NewLogFile CreateLogFile(const std::string& logs_dir, const std::string& name, bool overwrite);

}  // namespace sim4cv::daemon
