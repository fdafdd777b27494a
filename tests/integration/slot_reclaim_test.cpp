// Connection slots at capacity (--max-clients, --http-max-clients): a
// process that keeps opening connections and sending half a request holds
// no slot against well-behaved clients. The oldest connection that has
// completed nothing (no Hello, no request) makes room for each newcomer;
// before, the newcomer was refused until the half-open ones timed out (10 s).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <deque>

#include "tests/integration/daemon_fixture.h"
#include "tests/integration/raw_connection.h"

namespace sim4cv::testing {
namespace {

// One complete HTTP GET of "/" on a fresh connection: the status code, 0 if none came.
int HttpGetStatus(uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(port);
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  timeval timeout{10, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  int status = 0;
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) {
    const std::string request = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
    if (::write(fd, request.data(), request.size()) == static_cast<ssize_t>(request.size())) {
      char head[64] = {};
      if (::read(fd, head, sizeof head - 1) > 12) status = std::atoi(head + 9);  // "HTTP/1.1 200"
    }
  }
  ::close(fd);
  return status;
}

class SlotReclaimTest : public DaemonTest {};

TEST_F(SlotReclaimTest, AReconnectingSlowlorisLeavesTcpAndHttpSlotsToWellBehavedClients) {
  StartDaemon({"--max-clients", "4", "--http-port", "0", "--http-max-clients", "4"});
  const uint16_t http = static_cast<uint16_t>(std::stoi(ListeningField(daemon_->listening_line(), "http")));
  std::deque<std::unique_ptr<RawConnection>> slowloris;
  for (int i = 0; i < 4; ++i) {
    slowloris.push_back(std::make_unique<RawConnection>(daemon_->tcp_port()));
    EXPECT_TRUE(slowloris.back()->Send(std::string(2, '\0')));  // half a length prefix, and then nothing
    slowloris.push_back(std::make_unique<RawConnection>(http));
    EXPECT_TRUE(slowloris.back()->Send("GET / HT"));
  }
  for (int round = 0; round < 10; ++round) {
    // It reconnects as soon as it can: one more half-open connection on each port.
    slowloris.push_back(std::make_unique<RawConnection>(daemon_->tcp_port()));
    slowloris.back()->Send(std::string(2, '\0'));
    slowloris.push_back(std::make_unique<RawConnection>(http));
    slowloris.back()->Send("GET / HT");
    try {
      Connect("well-behaved-" + std::to_string(round))->GetWorld();
    } catch (const std::exception& error) {
      ADD_FAILURE() << "round " << round << ": a well-behaved TCP client was refused: " << error.what();
    }
    EXPECT_EQ(HttpGetStatus(http), 200) << "round " << round << ": a well-behaved HTTP request was not served";
  }
  EXPECT_NE(daemon_->stderr_text().find("had not completed its Hello, and a new connection needs its slot"),
            std::string::npos);
}

}  // namespace
}  // namespace sim4cv::testing
