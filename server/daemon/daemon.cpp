#include "server/daemon/daemon.h"

#include <signal.h>

#include <cstdio>
#include <memory>
#include <vector>

#include "protocol/framing.h"
#include "server/common/check.h"
#include "server/common/diagnostics.h"
#include "server/daemon/access_token_files.h"
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

// The token file names of the endpoints (AccessTokenFiles): "tcp-5000",
// "udp-5001", "http-8080", "shm-NAME"; clients look a file up by the
// address they were given.
std::vector<std::string> TokenFileNames(const std::vector<std::unique_ptr<transport::Transport>>& transports) {
  std::vector<std::string> names;
  for (const auto& t : transports) {
    const proto::TransportInfo info = t->info();
    std::string address = info.address();
    if (!address.empty() && address.front() == '/') address.erase(0, 1);  // shm names may start with '/'
    switch (info.kind()) {
      case proto::TRANSPORT_KIND_TCP:
        names.push_back("tcp-" + address);
        break;
      case proto::TRANSPORT_KIND_UDP:
        names.push_back("udp-" + address);
        break;
      case proto::TRANSPORT_KIND_WEBSOCKET:
        names.push_back("http-" + address);
        break;
      default:
        if (address.find('/') == std::string::npos) names.push_back("shm-" + address);
        break;
    }
  }
  return names;
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
  // Before any transport starts: a client that reads the listening line finds the token's file.
  const std::string token = LoadOrMakeToken(config);
  std::unique_ptr<AccessTokenFiles> token_files;
  if (!token.empty()) {
    token_files = std::make_unique<AccessTokenFiles>(token, TokenFileNames(transports));
    LOG_INFO("clients must show the access token in " << token_files->paths().front()
                                                      << " (readable only by this user; docs/security.md)");
    if (config.http_port >= 0) {
      LOG_INFO("studio: open http://" << config.http_bind << ":" << transports.back()->info().address()
                                      << "/?token=$(cat " << TokenFolder() << "/http-"
                                      << transports.back()->info().address() << ".token)");
    }
  } else {
    LOG_WARNING("--no-auth: every local user can drive this daemon and make it write files");
  }
  const session::ServerContext context{scene,
                                       config.mode,
                                       MakeWelcome(config, transports),
                                       directory,
                                       commands,
                                       latest_state,
                                       config.max_message_bytes,
                                       counters,
                                       token,
                                       token_files ? token_files->paths().front() : std::string()};
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
