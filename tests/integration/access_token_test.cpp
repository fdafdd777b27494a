// Who may drive the daemon (docs/security.md), against the real daemon: the
// token file only its user can read, Hello refused without the token over
// TCP and UDP, a second local user (nobody) that cannot read it and is
// refused, --token-file, and --no-auth only on loopback.
#include <grp.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "sim4cv/udp_client.h"
#include "tests/integration/daemon_fixture.h"
#include "tests/integration/raw_connection.h"
#include "tests/integration/run_log_fixture.h"

namespace sim4cv::testing {
namespace {

namespace fs = std::filesystem;

std::string TokenFolder() {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  if (runtime != nullptr && *runtime == '/') return std::string(runtime) + "/sim4cv";
  return std::string(std::getenv("HOME")) + "/.cache/sim4cv";
}

// The Error a Hello with `token` gets over a raw TCP connection, or "" for a Welcome.
std::string HelloRefusal(uint16_t port, const std::string& token) {
  RawConnection raw(port);
  EXPECT_TRUE(raw.Send(FramedHello("raw", token)));
  const auto reply = raw.Receive();
  if (!reply) return "no reply";
  if (reply->has_welcome()) return "";
  EXPECT_EQ(reply->error().code(), proto::ERROR_CODE_UNAUTHENTICATED) << reply->ShortDebugString();
  EXPECT_TRUE(reply->error().fatal());
  return reply->error().message();
}

class AccessTokenTest : public DaemonTest {};

TEST_F(AccessTokenTest, OnlyTheDaemonsUserCanReadTheTokenAndHelloNeedsIt) {
  StartDaemon();
  const std::string path = TokenFolder() + "/tcp-" + std::to_string(daemon_->tcp_port()) + ".token";
  struct stat info {};
  ASSERT_EQ(::stat(path.c_str(), &info), 0) << path;
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  EXPECT_EQ(info.st_uid, ::geteuid());
  ASSERT_EQ(::stat(TokenFolder().c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0700u);
  const std::string token = daemon_->access_token();
  EXPECT_EQ(token.size(), 64u);
  EXPECT_EQ(token.find_first_not_of("0123456789abcdef"), std::string::npos);
  EXPECT_EQ(daemon_->listening_line().find(token), std::string::npos) << "the token is not printed on stdout";
  EXPECT_NE(daemon_->stderr_text().find(path), std::string::npos) << "stderr names the token's file";

  const std::string refusal = HelloRefusal(daemon_->tcp_port(), "");
  for (const std::string& part : std::vector<std::string>{"Hello carries no access token", path, "SIM4CV_TOKEN",
                                                            "docs/security.md"}) {
    EXPECT_NE(refusal.find(part), std::string::npos) << part << " not in: " << refusal;
  }
  EXPECT_NE(HelloRefusal(daemon_->tcp_port(), std::string(64, '0')).find("not this daemon's access token"),
            std::string::npos);
  EXPECT_EQ(HelloRefusal(daemon_->tcp_port(), token), "");
  Connect("same-user")->GetWorld();  // the client reads the file by itself

  // UDP: the same Hello, the same refusal.
  const uint16_t udp_port = static_cast<uint16_t>(std::stoi(ListeningField(daemon_->listening_line(), "udp")));
  ::setenv("SIM4CV_TOKEN", "a-wrong-token-of-some-length", 1);
  UdpClient udp;
  try {
    udp.Connect("127.0.0.1", udp_port, "udp-stranger", std::chrono::seconds(5));
    ADD_FAILURE() << "a UDP Hello with a wrong token was welcomed";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_UNAUTHENTICATED) << error.what();
  }
  ::setenv("SIM4CV_TOKEN", token.c_str(), 1);
  udp.Connect("127.0.0.1", udp_port, "udp-with-env", std::chrono::seconds(5));
  ::unsetenv("SIM4CV_TOKEN");
  udp.Close();

  const int port = daemon_->tcp_port();
  EXPECT_EQ(daemon_->Stop(), 0);
  daemon_.reset();
  EXPECT_FALSE(fs::exists(path)) << "the daemon removes its token file when it stops";
  (void)port;
}

// What a process of user `nobody` gets: 0 when it is refused as it should
// be, else a code naming what went wrong.
int AsNobody(uint16_t port, const std::string& token_path) {
  if (::setgroups(0, nullptr) != 0 || ::setgid(65534) != 0 || ::setuid(65534) != 0) return 10;
  std::ifstream file(token_path);
  if (file.is_open()) return 11;  // it could read the token
  try {
    Client client;
    client.Connect("127.0.0.1", port, "nobody");
    return 12;  // welcomed
  } catch (const ServerError& error) {
    return error.code() == proto::ERROR_CODE_UNAUTHENTICATED ? 0 : 13;
  } catch (...) {
    return 14;
  }
}

TEST_F(AccessTokenTest, AnotherLocalUserCannotReadTheTokenAndIsRefused) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to run a process as nobody";
  StartDaemon();
  const std::string path = TokenFolder() + "/tcp-" + std::to_string(daemon_->tcp_port()) + ".token";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(AsNobody(daemon_->tcp_port(), path));
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "10: could not become nobody, 11: nobody read the token, 12: nobody was "
                                       "welcomed, 13/14: another error";
  EXPECT_NE(daemon_->stderr_text().find("('nobody') refused: no access token"), std::string::npos)
      << daemon_->stderr_text();
  Connect("owner")->GetWorld();  // the daemon's own user is still served
}

TEST_F(AccessTokenTest, ATokenFileGivesTheTokenAndNoAuthIsOnlyForLoopback) {
  ScratchDir dir;
  const std::string token_file = dir / "token";
  std::ofstream(token_file) << "a-shared-cluster-secret-of-enough-length\n";
  StartDaemon({"--token-file", token_file});
  EXPECT_EQ(daemon_->access_token(), "a-shared-cluster-secret-of-enough-length");
  EXPECT_EQ(HelloRefusal(daemon_->tcp_port(), "a-shared-cluster-secret-of-enough-length"), "");
  EXPECT_EQ(daemon_->Stop(), 0);
  daemon_.reset();

  try {
    DaemonProcess open_to_all({"--no-auth", "--bind", "0.0.0.0"});
    ADD_FAILURE() << "--no-auth was accepted on 0.0.0.0";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("--no-auth admits anyone who reaches the ports, so only with a loopback"),
              std::string::npos)
        << error.what();
  }
  DaemonProcess loopback({"--no-auth"});
  EXPECT_EQ(HelloRefusal(loopback.tcp_port(), ""), "") << "--no-auth on loopback admits a Hello without a token";
  EXPECT_EQ(loopback.Stop(), 0);
}

}  // namespace
}  // namespace sim4cv::testing
