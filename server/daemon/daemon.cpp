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
#include "server/daemon/transports.h"

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

  std::vector<std::unique_ptr<transport::Transport>> transports = MakeTransports(config, scene);

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
    for (const auto& t : transports) {
      if (t->info().kind() != proto::TRANSPORT_KIND_WEBSOCKET) continue;
      LOG_INFO("studio: open http://" << config.http_bind << ":" << t->info().address() << "/?token=$(cat "
                                      << TokenFolder() << "/http-" << t->info().address() << ".token)");
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
