#include "server/daemon/map_authoring.h"

#include <stdexcept>

#include "server/daemon/configure_error.h"
#include "server/sim/map/generator.h"
#include "server/sim/map/map_text.h"

namespace sim4cv::daemon {
namespace {

map::Map Parsed(const std::string& text, const std::string& field) {
  try {
    return map::ParseMap(text);
  } catch (const std::invalid_argument& error) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, field + ": " + error.what());
  }
}

}  // namespace

void CheckMapText(const std::string& text, const std::string& field) { Parsed(text, field); }

std::string CanonicalMapText(const std::string& text, const std::string& field) {
  return map::WriteMap(Parsed(text, field));
}

std::string GeneratedMapText(const proto::GenerateMap& request) {
  map::GeneratorOptions options;
  options.seed = request.seed() == 0 ? 1 : request.seed();
  options.width = request.width() == 0 ? 10 : static_cast<int>(request.width());
  options.height = request.height() == 0 ? 10 : static_cast<int>(request.height());
  if (request.tile_size() > 0) options.tile_size = request.tile_size();
  if (request.has_roadside_trees()) options.roadside_trees = request.roadside_trees();
  if (!request.name().empty()) options.name = request.name();
  std::string text;
  try {
    if (!request.surroundings().empty()) {
      const auto surroundings = map::SurroundingsFromName(request.surroundings());
      if (!surroundings) throw std::invalid_argument("surroundings must be 'desert' or 'urban'");
      options.surroundings = *surroundings;
    }
    if (request.layout_text().empty()) {
      text = map::GenerateMapText(options);
    } else {
      map::Map layout = Parsed(request.layout_text(), "GenerateMap.layout_text");
      layout.objects.clear();
      if (!request.name().empty()) layout.name = options.name;
      if (!request.surroundings().empty()) layout.surroundings = options.surroundings;
      map::Dress(layout, options.seed, options.roadside_trees);
      text = map::WriteMap(layout);
    }
  } catch (const std::invalid_argument& error) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, std::string("GenerateMap: ") + error.what());
  }
  // What the generator made must pass the parser every client's map passes
  // (a client's layout can exceed the road-tile limit, for one; generated roads never do).
  CheckMapText(text, "GenerateMap made a map the parser refuses (try a smaller grid or another seed)");
  return text;
}

}  // namespace sim4cv::daemon
