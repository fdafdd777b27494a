// The files clients name (OpenMap, SaveMap, LoadMap.name, StartLog) against
// the real daemon, with another local user's tricks: a folder of the name
// swapped for a symbolic link to a folder outside, back and forth, while
// the requests run (a check made before opening would be raced), LoadMap.name
// through a link (whose target's text an Error must not quote), and names
// the file system cannot hold, refused before anything is created.
#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "tests/integration/ring_map.h"
#include "tests/integration/run_log_fixture.h"
#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

namespace fs = std::filesystem;

constexpr char kSecret[] = "the secret first line of a file outside the maps folder\n";

// Exchanges two names (a real folder and a link to one outside) atomically,
// as fast as it can, until stopped: at every moment the name inside is one
// or the other.
class Swapper {
 public:
  Swapper(fs::path a, fs::path b) : a_(std::move(a)), b_(std::move(b)) {
    thread_ = std::thread([this] {
      while (!stop_.load(std::memory_order_relaxed)) {
        ::renameat2(AT_FDCWD, a_.c_str(), AT_FDCWD, b_.c_str(), RENAME_EXCHANGE);
        swaps_.fetch_add(1, std::memory_order_relaxed);
      }
    });
  }
  ~Swapper() {
    stop_ = true;
    thread_.join();
  }
  long swaps() const { return swaps_.load(); }

 private:
  fs::path a_, b_;
  std::atomic<bool> stop_{false};
  std::atomic<long> swaps_{0};
  std::thread thread_;
};

class NamedFilesRaceTest : public ConfigureTest {
 protected:
  void SetUp() override {
    fs::create_directories(fs::path(maps_ / "town"));
    std::ofstream(maps_ / "town/ring.map") << kRing;
    std::ofstream(outside_ / "ring.map") << kSecret;
    std::ofstream(outside_ / "log.s4log") << kSecret;
    StartDaemon({"--maps-dir", maps_ / "", "--logs-dir", maps_ / ""});
    client_ = Connect("editor");
  }

  proto::Configured Ask(const std::function<void(proto::Configure&)>& fill) {
    proto::Configure request;
    fill(request);
    return client_->Configure(request);
  }

  ScratchDir maps_;
  ScratchDir outside_;
  std::unique_ptr<Client> client_;
};

TEST_F(NamedFilesRaceTest, LoadMapByNameFollowsNoLinkAndQuotesNothingOfItsTarget) {
  fs::create_directory_symlink(outside_ / "", maps_ / "link");
  ExpectRefused([&] { client_->LoadMapByName("link/ring"); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"LoadMap", "symbolic link", "--maps-dir"});
  try {
    client_->LoadMapByName("link/ring");
  } catch (const ServerError& error) {
    EXPECT_EQ(std::string(error.what()).find("secret"), std::string::npos) << error.what();
  }
  // The file itself a link, into the folder or out of it: refused too.
  fs::create_symlink(outside_ / "ring.map", maps_ / "town/leak.map");
  ExpectRefused([&] { client_->LoadMapByName("town/leak"); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"symbolic link"});
  EXPECT_EQ(client_->LoadMapByName("town/ring").scene_name(), "ring");
}

TEST_F(NamedFilesRaceTest, AFolderSwappedForALinkWhileRequestsRunIsNeverFollowed) {
  fs::create_directories(fs::path(maps_ / "swap"));
  std::ofstream(maps_ / "swap/ring.map") << kRing;
  std::ofstream(maps_ / "swap/log.s4log") << "a log";
  fs::create_directory_symlink(outside_ / "", maps_ / "spare");
  int opened = 0, refused = 0;
  {
    const Swapper swapper(maps_ / "swap", maps_ / "spare");
    for (int i = 0; i < 150; ++i) {
      try {
        const std::string text = Ask([](proto::Configure& c) { c.mutable_open_map()->set_name("swap/ring"); }).map_text();
        ASSERT_EQ(text, kRing) << "OpenMap read a file outside --maps-dir";
        ++opened;
      } catch (const ServerError& error) {
        ASSERT_NE(std::string(error.what()).find("symbolic link"), std::string::npos) << error.what();
        ++refused;
      }
      try {
        Ask([](proto::Configure& c) {
          c.mutable_save_map()->set_name("swap/saved");
          c.mutable_save_map()->set_text(kRing);
          c.mutable_save_map()->set_overwrite(true);
        });
      } catch (const ServerError& error) {
        ASSERT_NE(std::string(error.what()).find("symbolic link"), std::string::npos) << error.what();
      }
      try {
        Ask([](proto::Configure& c) {
          c.mutable_start_log()->set_name("swap/log");
          c.mutable_start_log()->set_overwrite(true);
        });
        Ask([](proto::Configure& c) { c.mutable_stop_log(); });
      } catch (const ServerError& error) {
        ASSERT_NE(std::string(error.what()).find("symbolic link"), std::string::npos) << error.what();
      }
    }
    EXPECT_GT(swapper.swaps(), 1000) << "the swaps did not race the requests";
  }
  EXPECT_GT(opened + refused, 0);
  EXPECT_EQ(FileText(outside_ / "ring.map"), kSecret);
  EXPECT_EQ(FileText(outside_ / "log.s4log"), kSecret) << "StartLog with overwrite truncated a file outside --logs-dir";
  EXPECT_FALSE(fs::exists(fs::path(outside_ / "saved.map"))) << "SaveMap wrote into a folder outside --maps-dir";
  std::size_t outside_files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(outside_ / "")) ++outside_files;
  EXPECT_EQ(outside_files, 2u) << "something was created outside the folders";
}

TEST_F(NamedFilesRaceTest, ANameTheFileSystemCannotHoldIsRefusedBeforeAnythingIsMade) {
  const std::string part(253, 'a');
  ExpectRefused(
      [&] {
        Ask([&](proto::Configure& c) {
          c.mutable_save_map()->set_name("new_folder/" + part);
          c.mutable_save_map()->set_text(kRing);
        });
      },
      proto::ERROR_CODE_INVALID_ARGUMENT, {"SaveMap.name", "a part at most 200", "limits::kMaxFileNamePartBytes"});
  EXPECT_FALSE(fs::exists(fs::path(maps_ / "new_folder"))) << "a refused SaveMap made its folder";
  ExpectRefused([&] { Ask([&](proto::Configure& c) { c.mutable_start_log()->set_name("logs/" + part); }); },
                proto::ERROR_CODE_INVALID_ARGUMENT, {"StartLog.name", "a part at most 200"});
  EXPECT_FALSE(fs::exists(fs::path(maps_ / "logs")));
}

TEST_F(NamedFilesRaceTest, SaveMapKeepsEachFoldersQuotaOfFilesAndBytes) {
  const auto save = [&](const std::string& name) {
    Ask([&](proto::Configure& c) {
      c.mutable_save_map()->set_name(name);
      c.mutable_save_map()->set_text(kRing);
      c.mutable_save_map()->set_overwrite(true);
    });
  };
  fs::create_directories(fs::path(maps_ / "many"));
  for (int i = 0; i < 1000; ++i) std::ofstream(maps_ / ("many/m" + std::to_string(i) + ".map")) << kRing;
  ExpectRefused([&] { save("many/one_more"); }, proto::ERROR_CODE_IO,
                {"SaveMap: the folder", "would hold 1001 maps", "at most 1000 maps", "limits::kMaxMapsPerFolder"});
  save("many/m7");  // replacing one keeps the count
  fs::create_directories(fs::path(maps_ / "big"));
  std::ofstream(maps_ / "big/huge.map") << kRing;
  fs::resize_file(fs::path(maps_ / "big/huge.map"), 64u << 20);  // sparse: 64 MiB in name only
  ExpectRefused([&] { save("big/small"); }, proto::ERROR_CODE_IO, {"bytes; a folder holds at most", "67108864 bytes"});
  EXPECT_FALSE(fs::exists(fs::path(maps_ / "big/small.map")));
  save("other/small");  // another folder has its own quota
}

}  // namespace
}  // namespace sim4cv::testing
