#include "server/daemon/daemon.h"

#include <signal.h>

#include <cstdio>
#include <memory>
#include <vector>

#include "protocol/framing.h"
#include "server/common/check.h"
#include "server/common/diagnostics.h"
#include "server/daemon/sim_thread.h"
#include "server/daemon/state_message.h"
#include "server/transport/http/http_transport.h"
#include "server/transport/shm/shm_transport.h"
#include "server/transport/tcp/tcp_transport.h"
#include "server/transport/udp/udp_transport.h"

namespace sim4cv::daemon {
namespace {

diagnostics::Level ParseLevel(const std::string& name) {
  if (name == "debug") return diagnostics::Level::kDebug;
  if (name == "warning") return diagnostics::Level::kWarning;
  if (name == "error") return diagnostics::Level::kError;
  return diagnostics::Level::kInfo;
}

// The fixed part of every Welcome; the scene's name, cameras and entities
// come from the WorldDirectory when a client says Hello.
proto::Welcome MakeWelcome(const Config& config, const std::vector<std::unique_ptr<transport::Transport>>& transports) {
  proto::Welcome welcome;
  welcome.set_protocol_version(wire::kProtocolVersion);
  welcome.set_server_version(SIM4CV_VERSION);
  for (const auto& t : transports) *welcome.add_transports() = t->info();
  welcome.set_mode(config.mode);
  welcome.set_physics_hz(config.physics_hz);
  welcome.set_frame_hz(config.frame_hz);
  return welcome;
}

}  // namespace

int RunDaemon(const Config& config) {
  diagnostics::SetMinLevel(ParseLevel(config.log_level));
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  signal(SIGPIPE, SIG_IGN);  // a client that vanishes must not kill the daemon
  signal(SIGXFSZ, SIG_IGN);  // a run log over the file size limit is a write error, not death

  sim::Scene loaded = !config.map_file.empty()    ? sim::SceneFromMap(config.map_file, config.route, config.car_speed,
                                                                      config.width, config.height)
                      : config.scene_file.empty() ? sim::DefaultScene(config.width, config.height)
                                                  : sim::LoadSceneFile(config.scene_file, config.width, config.height);
  sim::AddTraffic(loaded, config.traffic);
  const auto initial_scene = std::make_shared<const sim::Scene>(std::move(loaded));
  const sim::Scene& scene = *initial_scene;

  std::vector<std::unique_ptr<transport::Transport>> transports;
  transports.push_back(
      transport::MakeTcpTransport({config.bind_address,
                                   config.tcp_port,
                                   config.max_clients,
                                   config.max_message_bytes,
                                   config.tcp_send_buffer_bytes,
                                   {config.handshake_timeout_ms, config.message_timeout_ms, config.idle_timeout_ms}}));
  if (config.udp_port >= 0) {
    transports.push_back(
        transport::MakeUdpTransport({config.bind_address, static_cast<uint16_t>(config.udp_port),
                                     config.udp_datagram_bytes, config.udp_expiry_ms, config.max_clients}));
  }
  if (!config.shm_name.empty()) {
    const int shm_camera = scene.FindCamera(config.shm_camera);
    SIM4CV_THROW_UNLESS(shm_camera >= 0,
                        "--shm-camera '" << config.shm_camera << "' is not a camera of scene '" << scene.name << "'");
    const auto& camera = scene.cameras[static_cast<std::size_t>(shm_camera)];
    transport::ShmOptions shm{config.shm_name, config.shm_camera, config.shm_slots};
    shm.width = camera.width;
    shm.height = camera.height;
    shm.expiry_ms = config.shm_expiry_ms;
    shm.channel_mask = config.shm_channel_mask;
    transports.push_back(transport::MakeShmTransport(shm));
  }
  if (config.http_port >= 0) {
    transport::HttpOptions http;
    http.bind_address = config.http_bind;
    http.port = static_cast<uint16_t>(config.http_port);
    http.max_clients = config.http_max_clients;
    http.other_connections = config.max_clients;  // TCP's, for the descriptor check
    http.studio_dir = config.studio_dir;
    http.timeouts = {config.handshake_timeout_ms, config.message_timeout_ms, config.idle_timeout_ms};
    http.send_buffer_bytes = config.tcp_send_buffer_bytes;
    transports.push_back(transport::MakeHttpTransport(http));
  }

  session::CommandQueue commands;
  session::LatestState latest_state;
  session::Counters counters;
  session::WorldDirectory directory;
  const session::ServerContext context{scene,    config.mode,  MakeWelcome(config, transports), directory,
                                       commands, latest_state, config.max_message_bytes,        counters};
  SimThread sim(config, initial_scene, commands, latest_state, directory, counters);
  sim.Start();
  for (auto& t : transports) t->Start(context);

  std::string line = "sim4cvd listening";
  for (const auto& t : transports) line.append(" ").append(t->listening_field());
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
  LOG_INFO("scene '" << scene.name << "', " << config.width << "x" << config.height << ", "
                     << (config.mode == proto::SIM_MODE_LOCKSTEP ? "lockstep" : "realtime") << " mode, "
                     << conditions::Describe(config.conditions) << ", renderer " << sim.renderer_name());

  int signal_number = 0;
  sigwait(&stop_signals, &signal_number);
  LOG_INFO("received signal " << signal_number << "; shutting down");
  sim.Stop();  // no new frames from here on
  for (auto& t : transports) t->Stop();
  transports.clear();  // sessions release their frames before the sim's pools go
  for (const auto& [name, value] : counters.Snapshot()) LOG_INFO("counter " << name << " = " << value);
  if (sim.failed()) {
    LOG_ERROR("stopped after the simulation failed (see above); the run log, if any, is closed");
    return 1;
  }
  LOG_INFO("stopped cleanly");
  return 0;
}

}  // namespace sim4cv::daemon
