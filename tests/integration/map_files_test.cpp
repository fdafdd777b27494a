// The studio editor's map requests against the real daemon, over TCP like
// any client: CheckMap and GenerateMap leave the world alone, OpenMap and
// SaveMap read and write only under --maps-dir (a temporary folder here),
// never follow a symbolic link out of it, never write a map the parser
// refuses, and never leave half a file.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/integration/ring_map.h"
#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

namespace fs = std::filesystem;


class MapFilesTest : public ConfigureTest {
 protected:
  void SetUp() override {
    maps_ = fs::temp_directory_path() / ("sim4cv_map_files_" + std::to_string(::getpid()));
    fs::remove_all(maps_);
    fs::create_directories(maps_ / "town");
    std::ofstream(maps_ / "town" / "ring.map") << kRing;
    StartDaemon({"--maps-dir", maps_.string()});
    client_ = Connect("editor");
  }
  void TearDown() override {
    ConfigureTest::TearDown();
    fs::remove_all(maps_);
  }

  proto::Configured Ask(const std::function<void(proto::Configure&)>& fill) {
    proto::Configure request;
    fill(request);
    return client_->Configure(request);
  }
  proto::Configured Save(const std::string& name, const std::string& text, bool overwrite = false) {
    return Ask([&](proto::Configure& c) {
      c.mutable_save_map()->set_name(name);
      c.mutable_save_map()->set_text(text);
      c.mutable_save_map()->set_overwrite(overwrite);
    });
  }
  std::string Open(const std::string& name) {
    return Ask([&](proto::Configure& c) { c.mutable_open_map()->set_name(name); }).map_text();
  }

  fs::path maps_;
  std::unique_ptr<Client> client_;
};

TEST_F(MapFilesTest, SaveThenOpenRoundTripsTheBytesAndListMapsAndLoadMapSeeIt) {
  // Not canonical (a comment, no blank surroundings line): written as sent.
  const std::string text = std::string(kRing) + "# drawn by hand\nobject tree 0 0 15\n";
  Save("studio/my_ring", text);
  EXPECT_EQ(FileText(maps_ / "studio" / "my_ring.map"), text);
  EXPECT_EQ(Open("studio/my_ring"), text);
  EXPECT_EQ(Open("town/ring"), kRing);
  const auto listed = Ask([](proto::Configure& c) { c.mutable_list_maps(); }).maps();
  EXPECT_EQ(std::vector<std::string>(listed.begin(), listed.end()),
            (std::vector<std::string>{"studio/my_ring", "town/ring"}));
  EXPECT_EQ(client_->LoadMapByName("studio/my_ring").scene_name(), "ring");
  for (const auto& entry : fs::directory_iterator(maps_ / "studio")) {
    EXPECT_EQ(entry.path().filename(), "my_ring.map") << "a temporary file was left behind";
  }

  ExpectRefused([&] { Save("studio/my_ring", kRing); }, proto::ERROR_CODE_ALREADY_EXISTS,
                {"my_ring.map' exists", "overwrite"});
  Save("studio/my_ring", kRing, /*overwrite=*/true);
  EXPECT_EQ(Open("studio/my_ring"), kRing);
}

TEST_F(MapFilesTest, AMapWithErrorsIsNotSavedAndTheFileIsUnchanged) {
  const std::string broken = std::string(kRing) + "object tree 0 0\n";
  ExpectRefused([&] { Save("town/ring", broken, true); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"SaveMap.text (not saved; the file on disk is unchanged)", "line 12", "object tree 0 0"});
  EXPECT_EQ(FileText(maps_ / "town" / "ring.map"), kRing);
  ExpectRefused([&] { Ask([&](proto::Configure& c) { c.mutable_check_map()->set_text(broken); }); },
                proto::ERROR_CODE_INVALID_ARGUMENT, {"CheckMap.text: map line 12 'object tree 0 0'"});
}

TEST_F(MapFilesTest, PathsOutsideTheMapsFolderAreRefused) {
  for (const char* name :
       {"../escape", "/etc/passwd", "town/../../escape", ".hidden", "town//ring", "town/", "a b", ""}) {
    ExpectRefused([&] { Save(name, kRing); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"SaveMap.name"});
    ExpectRefused([&] { Open(name); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"OpenMap.name"});
  }
  EXPECT_FALSE(fs::exists(maps_.parent_path() / "escape.map"));

  // A symbolic link inside the folder is not followed out of it.
  const fs::path outside = maps_.string() + "_outside";
  fs::create_directories(outside);
  fs::create_directory_symlink(outside, maps_ / "link");
  ExpectRefused([&] { Save("link/x", kRing); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"is a symbolic link"});
  ExpectRefused([&] { Open("link/x"); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"is a symbolic link"});
  EXPECT_TRUE(fs::is_empty(outside));
  fs::remove_all(outside);

  ExpectRefused([&] { Save("town/ring.map/x", kRing); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"is a file, not a folder"});
  ExpectRefused([&] { Open("town/none"); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"no such map"});
}

TEST_F(MapFilesTest, GenerateMapMatchesTheCommandLineGeneratorAndLeavesTheWorldAlone) {
  const std::string scene = client_->GetWorld().scene_name();
  const std::string text = Ask([](proto::Configure& c) {
                             c.mutable_generate_map()->set_seed(302);
                             c.mutable_generate_map()->set_width(12);
                             c.mutable_generate_map()->set_height(12);
                             c.mutable_generate_map()->set_surroundings("desert");
                             c.mutable_generate_map()->set_name("driving_test_02_desert");
                           }).map_text();
  EXPECT_EQ(text, FileText(fs::path(SIM4CV_SOURCE_DIR) / "scenes/driving/test/02_desert.map"))
      << "the shipped map was made by sim4cv_mapgen with these options";
  EXPECT_EQ(client_->GetWorld().scene_name(), scene);

  // Dressing a hand-drawn layout keeps its grid and routes.
  const std::string dressed = Ask([](proto::Configure& c) {
                                c.mutable_generate_map()->set_layout_text(kRing);
                                c.mutable_generate_map()->set_surroundings("urban");
                              }).map_text();
  EXPECT_NE(dressed.find("surroundings urban\ngrid 3 3\n###\n#.#\n###\nend\nroute loop closed\n"), std::string::npos)
      << dressed;
  ExpectRefused([&] { Ask([](proto::Configure& c) { c.mutable_generate_map()->set_width(40); }); },
                proto::ERROR_CODE_INVALID_ARGUMENT, {"GenerateMap.width is 40"});
  ExpectRefused([&] { Ask([](proto::Configure& c) { c.mutable_generate_map()->set_layout_text("sim4cv-map 1\n"); }); },
                proto::ERROR_CODE_INVALID_ARGUMENT, {"GenerateMap.layout_text"});
}

TEST_F(MapFilesTest, AMissingMapsFolderIsNamed) {
  fs::remove_all(maps_);
  ExpectRefused([&] { Save("a", kRing); }, proto::ERROR_CODE_IO, {"--maps-dir", "is not a folder"});
  EXPECT_FALSE(fs::exists(maps_)) << "the daemon does not make up a maps folder";
}

}  // namespace
}  // namespace sim4cv::testing
