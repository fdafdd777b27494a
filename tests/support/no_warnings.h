// Every test binary links no_warnings_main.cpp: a test that makes our code log
// a warning or an error fails (after MuJoCo's MujocoTest), unless it declares
// the lines it expects with ExpectLogged.
#pragma once

#include <string>

namespace sim4cv::testing {

// Within the current test, a warning/error line containing `substring` is
// expected; the test fails if no such line is logged by the end of the test.
void ExpectLogged(const std::string& substring);

}  // namespace sim4cv::testing
