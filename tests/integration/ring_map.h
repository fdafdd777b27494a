// The smallest valid map (a 3x3 ring road) and reading a file's bytes, for
// the tests of the map files clients name (map_files_test,
// named_files_race_test).
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace sim4cv::testing {

inline constexpr char kRing[] =
    "sim4cv-map 1\nname ring\ntile_size 20\nsurroundings desert\ngrid 3 3\n###\n#.#\n###\nend\n"
    "route loop closed\ntiles 0,0 0,1 0,2 1,2 2,2 2,1 2,0 1,0\n";

inline std::string FileText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace sim4cv::testing
