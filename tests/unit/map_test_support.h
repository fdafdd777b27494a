// Helpers shared by the map_*_test files: small maps written as text.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <initializer_list>
#include <stdexcept>
#include <string>

#include "server/sim/map/map_text.h"

namespace sim4cv::map::testing {

// A map with the given grid rows; `extra` lines (routes, objects) follow the grid.
inline std::string MapText(std::initializer_list<const char*> rows, double tile_size = 20.0,
                           const std::string& extra = "") {
  std::string text = "sim4cv-map 1\nname test\ntile_size " + std::to_string(tile_size) + "\n";
  text += "grid " + std::to_string(std::string(*rows.begin()).size()) + " " + std::to_string(rows.size()) + "\n";
  for (const char* row : rows) text += std::string(row) + "\n";
  return text + "end\n" + extra;
}

inline Map ParseRows(std::initializer_list<const char*> rows, double tile_size = 20.0, const std::string& extra = "") {
  return ParseMap(MapText(rows, tile_size, extra));
}

// The message ParseMap throws for `text`, or a test failure.
inline std::string ParseError(const std::string& text) {
  try {
    ParseMap(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no std::invalid_argument for:\n" << text;
  return {};
}

inline void ExpectNear(const Eigen::Vector2d& actual, const Eigen::Vector2d& expected, double tol = 1e-9) {
  EXPECT_NEAR((actual - expected).norm(), 0.0, tol)
      << "actual " << actual.transpose() << ", expected " << expected.transpose();
}

}  // namespace sim4cv::map::testing
