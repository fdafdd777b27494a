// Unit tests of the studio's HTTP transport's pure parts
// (server/transport/http): the JSON Envelope codec's errors, the WebSocket
// URL's view options, the Origin/Host check, and the page's files, which no
// URL may escape. The transport itself is tested against the real daemon
// (tests/studio).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "server/transport/http/http_connection.h"
#include "server/transport/http/json_envelope.h"
#include "server/transport/http/static_files.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::transport {
namespace {

namespace fs = std::filesystem;

TEST(JsonEnvelopeTest, ReadsTheProtoNamesAndWritesThemBack) {
  proto::Envelope envelope;
  ASSERT_EQ(EnvelopeFromJson(R"({"subscribe": {"camera": "uav", "channels": ["CHANNEL_RGB"],
                                                "delivery": "DELIVERY_NEWEST", "with_state": true}})",
                             envelope),
            "");
  EXPECT_EQ(envelope.subscribe().camera(), "uav");
  EXPECT_EQ(envelope.subscribe().delivery(), proto::DELIVERY_NEWEST);
  EXPECT_TRUE(envelope.subscribe().with_state());
  std::string json;
  envelope.Clear();
  envelope.mutable_state()->set_frame_id(12345678901234ull);
  EnvelopeToJson(envelope, json);
  EXPECT_EQ(json, R"({"state":{"frame_id":"12345678901234"}})");  // 64-bit integers as strings
}

TEST(JsonEnvelopeTest, ErrorsNameTheProblemAndStayShort) {
  proto::Envelope envelope;
  EXPECT_NE(EnvelopeFromJson("{not json", envelope), "");
  EXPECT_NE(EnvelopeFromJson(R"({"get_stat": {}})", envelope).find("get_stat"), std::string::npos);
  EXPECT_NE(EnvelopeFromJson(R"({"subscribe": {"delivery": "SOMETIMES"}})", envelope).find("SOMETIMES"),
            std::string::npos);
  const std::string huge = R"({"hello": {"protocol_version": ")" + std::string(100000, '9') + R"("}})";
  EXPECT_LT(EnvelopeFromJson(huge, envelope).size(), 300u);
}

// The codec's message types are resolved once and shared by every session's
// thread: the second and later calls, from any thread, read and write the same.
TEST(JsonEnvelopeTest, SessionThreadsShareTheResolvedTypes) {
  std::vector<std::thread> sessions;
  std::atomic<int> wrong{0};
  for (int t = 0; t < 4; ++t) {
    sessions.emplace_back([t, &wrong] {
      proto::Envelope envelope;
      std::string json;
      for (int i = 0; i < 50; ++i) {
        const std::string camera = "cam" + std::to_string(t * 100 + i);
        if (!EnvelopeFromJson(R"({"subscribe": {"camera": ")" + camera + R"(", "max_fps": 30}})", envelope).empty() ||
            envelope.subscribe().camera() != camera ||
            EnvelopeFromJson(R"({"subscribe": {"fps": 30}})", envelope).find("fps") == std::string::npos) {
          ++wrong;
        }
        envelope.Clear();
        envelope.mutable_subscribe()->set_camera(camera);
        envelope.mutable_subscribe()->set_delivery(proto::DELIVERY_NEWEST);
        EnvelopeToJson(envelope, json);
        if (json != R"({"subscribe":{"camera":")" + camera + R"(","delivery":"DELIVERY_NEWEST"}})") ++wrong;
      }
    });
  }
  for (auto& session : sessions) session.join();
  EXPECT_EQ(wrong.load(), 0);
}

TEST(ViewQueryTest, TakesRgbAndQualityAndNamesAnythingElse) {
  std::string problem;
  auto view = HttpConnection::ParseViewQuery("", problem);
  ASSERT_TRUE(view);
  EXPECT_TRUE(view->jpeg_rgb);
  view = HttpConnection::ParseViewQuery("rgb=raw&quality=95", problem);
  ASSERT_TRUE(view);
  EXPECT_FALSE(view->jpeg_rgb);
  EXPECT_EQ(view->jpeg_quality, 95);
  EXPECT_FALSE(HttpConnection::ParseViewQuery("quality=0", problem));
  EXPECT_NE(problem.find("1 to 100"), std::string::npos) << problem;
  EXPECT_FALSE(HttpConnection::ParseViewQuery("quality=9x", problem));
  EXPECT_FALSE(HttpConnection::ParseViewQuery("rgb=png", problem));
  EXPECT_NE(problem.find("rgb=png"), std::string::npos) << problem;
}

TEST(OriginCheckTest, OnlyTheStudiosOwnPageOnAnAddressOrLocalhost) {
  EXPECT_EQ(HttpConnection::CheckOrigin("", "127.0.0.1:8080"), "");  // not a browser
  EXPECT_EQ(HttpConnection::CheckOrigin("http://127.0.0.1:8080", "127.0.0.1:8080"), "");
  EXPECT_EQ(HttpConnection::CheckOrigin("http://localhost:8080", "localhost:8080"), "");
  EXPECT_EQ(HttpConnection::CheckOrigin("http://[::1]:8080", "[::1]:8080"), "");
  EXPECT_NE(HttpConnection::CheckOrigin("http://evil.example", "127.0.0.1:8080").find("evil.example"),
            std::string::npos);
  EXPECT_NE(HttpConnection::CheckOrigin("null", "127.0.0.1:8080"), "");
  // DNS rebinding: the page's origin matches, but the name is not an address.
  EXPECT_NE(HttpConnection::CheckOrigin("http://rebound.example:8080", "rebound.example:8080"), "");
  EXPECT_NE(HttpConnection::CheckOrigin("", ""), "");
}

class StaticFilesTest : public ::testing::Test {
 protected:
  StaticFilesTest() : root_(fs::temp_directory_path() / ("sim4cv-static-" + std::to_string(getpid()))) {
    fs::create_directories(root_ / "studio" / "js");
    Write(root_ / "studio" / "index.html", "<html>");
    Write(root_ / "studio" / "js" / "main.js", "let a;");
    Write(root_ / "studio" / "notes.md", "not served");
    Write(root_ / "secret.txt", "outside");
    fs::create_symlink(root_ / "secret.txt", root_ / "studio" / "link.txt");
    // Hidden files and folders are not the page's (an editor's backup, a checkout's .git).
    fs::create_directories(root_ / "studio" / ".git");
    Write(root_ / "studio" / ".git" / "config.txt", "hidden");
    Write(root_ / "studio" / ".env.json", "{}");
  }
  ~StaticFilesTest() override { fs::remove_all(root_); }
  static void Write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

  fs::path root_;
};

TEST_F(StaticFilesTest, ServesExactlyTheFilesItRead) {
  const StaticFiles files((root_ / "studio").string());
  EXPECT_EQ(files.count(), 2u);
  ASSERT_NE(files.Find("/"), nullptr);
  EXPECT_EQ(files.Find("/")->bytes, "<html>");
  EXPECT_EQ(files.Find("/index.html?x=1")->content_type, "text/html; charset=utf-8");
  ASSERT_NE(files.Find("/js/main.js"), nullptr);
  EXPECT_EQ(files.Find("/js/main.js")->content_type, "text/javascript; charset=utf-8");
  for (const char* target : {"/../secret.txt", "/js/../../secret.txt", "/%2e%2e/secret.txt", "/link.txt", "/notes.md",
                             "/.env.json", "/.git/config.txt",
                             "//index.html", "index.html", ""}) {
    EXPECT_EQ(files.Find(target), nullptr) << target;
  }
}

TEST_F(StaticFilesTest, AFolderWithoutIndexIsRefusedByName) {
  try {
    StaticFiles files((root_ / "studio" / "js").string());
    FAIL() << "no index.html, yet accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("has no index.html"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace sim4cv::transport
