#include <gtest/gtest.h>

#include <mutex>
#include <string>
#include <vector>

#include "server/common/diagnostics.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::testing {
namespace {

std::mutex g_mutex;
std::vector<std::string> g_logged;    // warnings and errors of the running test
std::vector<std::string> g_expected;  // substrings the running test declared

class FailOnWarnings : public ::testing::EmptyTestEventListener {
  void OnTestStart(const ::testing::TestInfo&) override {
    std::lock_guard lock(g_mutex);
    g_logged.clear();
    g_expected.clear();
  }
  void OnTestEnd(const ::testing::TestInfo&) override {
    std::lock_guard lock(g_mutex);
    std::vector<bool> expectation_met(g_expected.size(), false);
    for (const auto& line : g_logged) {
      bool expected = false;
      for (std::size_t i = 0; i < g_expected.size(); ++i) {
        if (line.find(g_expected[i]) != std::string::npos) expected = expectation_met[i] = true;
      }
      // ADD_FAILURE from OnTestEnd is attributed to the test that just ran.
      if (!expected) ADD_FAILURE() << "unexpected log line: " << line;
    }
    for (std::size_t i = 0; i < g_expected.size(); ++i) {
      if (!expectation_met[i]) ADD_FAILURE() << "expected a log line containing: " << g_expected[i];
    }
  }
};

}  // namespace

void ExpectLogged(const std::string& substring) {
  std::lock_guard lock(g_mutex);
  g_expected.push_back(substring);
}

}  // namespace sim4cv::testing

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  sim4cv::diagnostics::SetSink([](sim4cv::diagnostics::Level level, std::string_view text) {
    if (level < sim4cv::diagnostics::Level::kWarning) return;
    std::lock_guard lock(sim4cv::testing::g_mutex);
    sim4cv::testing::g_logged.emplace_back(std::string(sim4cv::diagnostics::LevelName(level)) + " " + std::string(text));
  });
  ::testing::UnitTest::GetInstance()->listeners().Append(new sim4cv::testing::FailOnWarnings);
  return RUN_ALL_TESTS();
}
