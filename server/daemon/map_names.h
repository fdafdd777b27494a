// The names LoadMap.name accepts (Configure.list_maps): every map file under
// --maps-dir. Read on the sim thread like LoadMap's own file, between frames.
#pragma once

#include <google/protobuf/repeated_ptr_field.h>

#include <string>

namespace sim4cv::daemon {

// Appends to `names` the path of every regular "*.map" file under `maps_dir`
// (recursively, symbolic links not followed), relative to it and without
// ".map", e.g. "tracking/easy_urban"; sorted, at most limits::kMaxListedMaps.
// A missing or unreadable folder lists nothing.
void ListMapNames(const std::string& maps_dir, google::protobuf::RepeatedPtrField<std::string>& names);

}  // namespace sim4cv::daemon
