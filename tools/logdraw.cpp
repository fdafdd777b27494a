// sim4cv_logdraw: draws the trajectories of run logs over their map, one
// colour per log (docs/logs.md#drawing-runs).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/sim/log/replay_track.h"
#include "server/sim/map/map_text.h"
#include "tools/log_drawing.h"

namespace {

using namespace sim4cv;

constexpr const char* kUsage =
    "usage: sim4cv_logdraw --map MAP_FILE --out PNG LOG [LOG...] [--entity NAME] [--scale PX_PER_M]\n"
    "  Draws MAP_FILE from above and, over it, the path of every UAV of each LOG (or of the\n"
    "  entity called NAME), one colour per path, with a legend naming the log files.\n"
    "  --scale  pixels per metre (default: about 1000 px on the longer side)\n";

struct Args {
  std::string map_path, out_path, entity;
  double scale = 0.0;
  std::vector<std::string> logs;
};

// Returns false (after printing why) on a bad command line.
bool ParseArgs(int argc, char** argv, Args* args) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if ((arg == "--map" || arg == "--out" || arg == "--entity" || arg == "--scale") && !has_value) {
      std::fprintf(stderr, "sim4cv_logdraw: %s needs a value\n", arg.c_str());
      return false;
    }
    if (arg == "--map") {
      args->map_path = argv[++i];
    } else if (arg == "--out") {
      args->out_path = argv[++i];
    } else if (arg == "--entity") {
      args->entity = argv[++i];
    } else if (arg == "--scale") {
      char* end = nullptr;
      args->scale = std::strtod(argv[++i], &end);
      if (*end != '\0' || !(args->scale > 0)) {
        std::fprintf(stderr, "sim4cv_logdraw: --scale wants a positive number, not '%s'\n", argv[i]);
        return false;
      }
    } else if (arg.starts_with("--")) {
      std::fprintf(stderr, "sim4cv_logdraw: unknown option %s\n", arg.c_str());
      return false;
    } else {
      args->logs.push_back(arg);
    }
  }
  if (args->map_path.empty() || args->out_path.empty() || args->logs.empty()) {
    std::fputs("sim4cv_logdraw: --map, --out and at least one LOG are required\n", stderr);
    return false;
  }
  return true;
}

std::string EntityNames(const runlog::RunLogHeader& header) {
  std::string names;
  for (const runlog::LogEntity& entity : header.entities) names += (names.empty() ? "" : ", ") + entity.name;
  return names.empty() ? "none" : names;
}

// The entities of one log to draw: the one named, or every UAV.
std::vector<const runlog::LogEntity*> ChooseEntities(const std::string& log, const runlog::RunLogHeader& header,
                                                     const std::string& name) {
  std::vector<const runlog::LogEntity*> chosen;
  if (!name.empty()) {
    if (const runlog::LogEntity* entity = header.FindEntity(name)) chosen.push_back(entity);
  } else {
    for (const runlog::LogEntity& entity : header.entities) {
      if (entity.kind == runlog::kEntityKindUav) chosen.push_back(&entity);
    }
  }
  if (chosen.empty()) {
    throw std::invalid_argument(log + ": no " + (name.empty() ? "UAV" : "entity called '" + name + "'") +
                                " in this log (its entities: " + EntityNames(header) + ")");
  }
  return chosen;
}

// "file.s4log (label): entity"; the entity only when it is not obvious.
std::string Legend(const std::string& log, const runlog::RunLogHeader& header, const runlog::LogEntity& entity,
                   bool name_entity) {
  std::string legend = std::filesystem::path(log).filename().string();
  if (!header.label.empty()) legend += " (" + header.label + ")";
  if (name_entity) legend += ": " + entity.name;
  return legend;
}

std::vector<tools::Track> LoadTracks(const Args& args, const map::Map& map) {
  std::vector<tools::Track> tracks;
  for (const std::string& log : args.logs) {
    const runlog::ReplayTrack replay = runlog::ReplayTrack::Load(log);
    const runlog::RunLogHeader& header = replay.header();
    if (replay.ignored_bytes() > 0) {
      std::fprintf(stderr, "sim4cv_logdraw: %s: ignored an incomplete record of %llu bytes at the end\n", log.c_str(),
                   static_cast<unsigned long long>(replay.ignored_bytes()));
    }
    if (!header.scene_name.empty() && header.scene_name != map.name) {
      std::fprintf(stderr, "sim4cv_logdraw: note: %s was recorded on '%s', drawn over map '%s'\n", log.c_str(),
                   header.scene_name.c_str(), map.name.c_str());
    }
    const auto entities = ChooseEntities(log, header, args.entity);
    for (const runlog::LogEntity* entity : entities) {
      tools::Track track{Legend(log, header, *entity, !args.entity.empty() || entities.size() > 1), {}};
      for (const Eigen::Vector3d& p : replay.PositionsOf(entity->id)) track.points.push_back(p.head<2>());
      tracks.push_back(std::move(track));
    }
  }
  return tracks;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  if (!ParseArgs(argc, argv, &args)) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  try {
    const map::Map map = map::LoadMapFile(args.map_path);
    const cv::Mat image = tools::DrawRunMap(map, LoadTracks(args, map), args.scale);
    if (!cv::imwrite(args.out_path, image)) throw std::runtime_error("cannot write " + args.out_path);
    std::printf("%s: %dx%d px, %zu logs\n", args.out_path.c_str(), image.cols, image.rows, args.logs.size());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sim4cv_logdraw: %s\n", e.what());
    return 1;
  }
}
