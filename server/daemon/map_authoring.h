// The studio editor's requests that make or check map text without touching
// the world: CheckMap (the daemon's parser as the one source of truth for
// the editor's inline errors) and GenerateMap (the seeded generator of
// sim4cv_mapgen). Pure functions of their request.
#pragma once

#include <string>

#include "sim4cv.pb.h"

namespace sim4cv::daemon {

// Refuses (ConfigureError INVALID_ARGUMENT, the parser's message prefixed
// with `field`) a map text the daemon's parser does not accept.
void CheckMapText(const std::string& text, const std::string& field);

// The canonical text of a map text that parses, or ConfigureError
// INVALID_ARGUMENT with the parser's message ("map line N 'LINE': ..."),
// prefixed with `field`.
std::string CanonicalMapText(const std::string& text, const std::string& field);

// The generated map's text: GenerateMapText's (with its "# sim4cv_mapgen"
// comment) or, with layout_text, that map re-dressed. Throws ConfigureError.
std::string GeneratedMapText(const proto::GenerateMap& request);

}  // namespace sim4cv::daemon
