#include "server/daemon/transports.h"

#include <mutex>

#include "server/common/check.h"
#include "server/transport/http/http_transport.h"
#include "server/transport/shm/shm_transport.h"
#include "server/transport/tcp/tcp_transport.h"
#include "server/transport/udp/udp_transport.h"

namespace sim4cv::daemon {
namespace {

std::unique_ptr<transport::Transport> MakeTcp(const Config& config, const sim::Scene&) {
  return transport::MakeTcpTransport({config.bind_address,
                                      config.tcp_port,
                                      config.max_clients,
                                      config.max_message_bytes,
                                      config.tcp_send_buffer_bytes,
                                      {config.handshake_timeout_ms, config.message_timeout_ms, config.idle_timeout_ms}});
}

std::unique_ptr<transport::Transport> MakeUdp(const Config& config, const sim::Scene&) {
  if (config.udp_port < 0) return nullptr;
  return transport::MakeUdpTransport({config.bind_address, static_cast<uint16_t>(config.udp_port),
                                      config.udp_datagram_bytes, config.udp_expiry_ms, config.max_clients});
}

std::unique_ptr<transport::Transport> MakeShm(const Config& config, const sim::Scene& scene) {
  if (config.shm_name.empty()) return nullptr;
  const int shm_camera = scene.FindCamera(config.shm_camera);
  SIM4CV_THROW_UNLESS(shm_camera >= 0,
                      "--shm-camera '" << config.shm_camera << "' is not a camera of scene '" << scene.name << "'");
  const auto& camera = scene.cameras[static_cast<std::size_t>(shm_camera)];
  transport::ShmOptions shm{config.shm_name, config.shm_camera, config.shm_slots};
  shm.width = camera.width;
  shm.height = camera.height;
  shm.expiry_ms = config.shm_expiry_ms;
  shm.channel_mask = config.shm_channel_mask;
  return transport::MakeShmTransport(shm);
}

std::unique_ptr<transport::Transport> MakeHttp(const Config& config, const sim::Scene&) {
  if (config.http_port < 0) return nullptr;
  transport::HttpOptions http;
  http.bind_address = config.http_bind;
  http.port = static_cast<uint16_t>(config.http_port);
  http.max_clients = config.http_max_clients;
  http.other_connections = config.max_clients;  // TCP's, for the descriptor check
  http.studio_dir = config.studio_dir;
  http.timeouts = {config.handshake_timeout_ms, config.message_timeout_ms, config.idle_timeout_ms};
  http.send_buffer_bytes = config.tcp_send_buffer_bytes;
  return transport::MakeHttpTransport(http);
}

// One line per transport. TCP comes first: the listening line starts with tcp=PORT.
const TransportEntry kTransports[] = {
    {"tcp", MakeTcp},
    {"udp", MakeUdp},
    {"shm", MakeShm},
    {"http", MakeHttp},
};

std::mutex registered_mutex;
std::vector<TransportEntry>& Registered() {
  static std::vector<TransportEntry> registered;
  return registered;
}

}  // namespace

void RegisterTransport(TransportEntry entry) {
  std::lock_guard lock(registered_mutex);
  Registered().push_back(entry);
}

std::vector<std::unique_ptr<transport::Transport>> MakeTransports(const Config& config, const sim::Scene& scene) {
  std::vector<TransportEntry> entries(std::begin(kTransports), std::end(kTransports));
  {
    std::lock_guard lock(registered_mutex);
    entries.insert(entries.end(), Registered().begin(), Registered().end());
  }
  std::vector<std::unique_ptr<transport::Transport>> transports;
  for (const TransportEntry& entry : entries) {
    if (auto made = entry.make(config, scene)) transports.push_back(std::move(made));
  }
  return transports;
}

}  // namespace sim4cv::daemon
