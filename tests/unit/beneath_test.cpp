// Opening beneath a folder's descriptor (server/common/beneath.h), with
// openat2 and with the walk used where the kernel has none: a link in any
// part is refused, never followed, and nothing climbs out of the folder.
#include "server/common/beneath.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>

namespace sim4cv {
namespace {

namespace fs = std::filesystem;

class BeneathTest : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override {
    char path[] = "/tmp/sim4cv-beneath-XXXXXX";
    ASSERT_NE(::mkdtemp(path), nullptr);
    root_ = path;
    fs::create_directories(root_ / "in/sub");
    fs::create_directories(root_.string() + "_outside");
    std::ofstream(root_ / "in/sub/file.txt") << "inside";
    std::ofstream(root_.string() + "_outside/file.txt") << "outside";
    fs::create_directory_symlink(root_.string() + "_outside", root_ / "in/link");
    fs::create_symlink(root_.string() + "_outside/file.txt", root_ / "in/sub/leaf.txt");
    folder_ = Fd(::open((root_ / "in").c_str(), O_RDONLY | O_DIRECTORY));
    ASSERT_TRUE(folder_.valid());
  }
  void TearDown() override {
    fs::remove_all(root_);
    fs::remove_all(root_.string() + "_outside");
  }
  // The errno of opening `relative` for reading, 0 if it opened.
  int OpenError(const std::string& relative) {
    const Fd fd(GetParam() ? OpenBeneathByWalk(folder_.get(), relative, O_RDONLY)
                           : OpenBeneath(folder_.get(), relative, O_RDONLY));
    return fd.valid() ? 0 : errno;
  }

  fs::path root_;
  Fd folder_;
};

TEST_P(BeneathTest, OpensFilesBeneathAndRefusesLinksAndEscapes) {
  EXPECT_EQ(OpenError("sub/file.txt"), 0);
  EXPECT_EQ(OpenError("link/file.txt"), ELOOP) << "a folder that is a link";
  EXPECT_EQ(OpenError("sub/leaf.txt"), ELOOP) << "a file that is a link";
  EXPECT_EQ(OpenError("sub/file.txt/x"), ENOTDIR);
  EXPECT_EQ(OpenError("../in/sub/file.txt"), EINVAL);
  EXPECT_EQ(OpenError("/etc/passwd"), EINVAL);
  EXPECT_EQ(OpenError("sub//file.txt"), EINVAL);
  EXPECT_EQ(OpenError("sub/./file.txt"), EINVAL);
}

TEST_P(BeneathTest, FoldersAreMadeButNeverThroughALink) {
  const Fd made(OpenFolderBeneath(folder_.get(), "new/deeper", true));
  EXPECT_TRUE(made.valid());
  EXPECT_TRUE(fs::is_directory(root_ / "in/new/deeper"));
  EXPECT_FALSE(Fd(OpenFolderBeneath(folder_.get(), "link/made", true)).valid());
  EXPECT_EQ(errno, ELOOP);
  EXPECT_FALSE(fs::exists(root_.string() + "_outside/made"));
  EXPECT_FALSE(Fd(OpenFolderBeneath(folder_.get(), "sub/file.txt", true)).valid());
  EXPECT_EQ(errno, ENOTDIR);
  EXPECT_EQ(SplitLeaf("a/b/c.map"), (std::pair<std::string, std::string>{"a/b", "c.map"}));
  EXPECT_EQ(SplitLeaf("c.map"), (std::pair<std::string, std::string>{"", "c.map"}));
}

INSTANTIATE_TEST_SUITE_P(OpenAt2AndWalk, BeneathTest, ::testing::Bool(),
                         [](const auto& info) { return info.param ? "walk" : "openat2"; });

}  // namespace
}  // namespace sim4cv
