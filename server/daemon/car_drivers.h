// Who drives which car with Controls, and the timeout that stops a car whose
// driver went quiet (docs/protocol.md, "Controls").
// A car takes Controls from one client at a time, so two clients cannot
// fight over it frame by frame; the first to send Controls owns it until it
// disconnects, its Controls time out, or the car goes (Remove, Reset,
// LoadMap) or returns to a route. Sim thread only: the network threads never
// see this state, so it needs no lock, and the timeout runs on simulation
// time (State::sim_time), so a lockstep run repeats exactly and a client that
// steps slowly is not punished.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "server/common/quoted.h"
#include "server/session/command.h"
#include "server/sim/state.h"

namespace sim4cv::daemon {

class CarDrivers {
 public:
  // `timeout_ms` is --controls-timeout-ms; 0 turns the timeout off.
  explicit CarDrivers(uint32_t timeout_ms) : timeout_ms_(timeout_ms) {}

  // Applies `controls` from `client` to `car` (a car of `state`) if no other
  // client drives it, and makes `client` its driver. Otherwise changes
  // nothing and returns the refusal for the client's Error.
  std::string Drive(sim::State& state, sim::Entity& car, session::ClientId client,
                    const session::ControlsCommand& controls) {
    const auto [it, taken] = drivers_.try_emplace(car.id, client);
    if (!taken && it->second != client) return Refusal(car, it->second);
    car.car_command = {controls.steering, controls.throttle, controls.brake, true, true, state.sim_time};
    return {};
  }

  // The client disconnected (its DisconnectCommand reached the sim thread):
  // its cars are free. They keep its last Controls until the timeout brakes them.
  void Release(session::ClientId client) {
    std::erase_if(drivers_, [client](const auto& entry) { return entry.second == client; });
  }

  // After a committed Configure: a new scene (Reset, LoadMap) frees every
  // car; otherwise a car that was removed, or that a SetRoute or SetSpeed
  // gave back to its route, is free.
  void AfterConfigure(const sim::State& state, bool new_scene) {
    if (new_scene) {
      drivers_.clear();
      return;
    }
    std::erase_if(drivers_, [&state](const auto& entry) {
      const sim::Entity* car = state.Find(entry.first);
      return !car || car->kind != sim::EntityKind::kCar || !car->car_command.manual;
    });
  }

  // Before a frame's physics: every car whose last Controls are more than
  // the timeout old brakes to a stop (throttle 0, brake 1, steering kept)
  // and is free; the next Controls take it again. Returns how many cars it
  // stopped (the daemon's counter controls.timeouts); logs nothing, as it
  // runs every frame.
  uint32_t BrakeStale(sim::State& state) {
    if (timeout_ms_ == 0) return 0;
    // 1 ns of slack: "more than N ms", robust to the rounding of sim_time.
    const double timeout_s = timeout_ms_ / 1000.0 + 1e-9;
    uint32_t stopped = 0;
    for (sim::Entity& car : state.entities) {
      sim::CarCommand& command = car.car_command;
      if (car.kind != sim::EntityKind::kCar || !command.manual || !command.from_controls) continue;
      if (state.sim_time - command.controls_time <= timeout_s) continue;
      command.throttle = 0.0f;
      command.brake = 1.0f;
      command.from_controls = false;  // stays manual: braked, not handed back to its route
      drivers_.erase(car.id);
      ++stopped;
    }
    return stopped;
  }

 private:
  std::string Refusal(const sim::Entity& car, session::ClientId driver) const {
    const std::string silence = timeout_ms_ == 0 ? std::string("(--controls-timeout-ms is 0: never by silence)")
                                                 : "or sends no Controls for " + std::to_string(timeout_ms_) +
                                                       " ms of simulation time (--controls-timeout-ms)";
    return "Controls for car " + std::to_string(car.id) + " (" + Quoted(car.name) + ") refused: another client (id " +
           std::to_string(driver) +
           ") drives it, and a car takes Controls from one client at a time. It becomes free when that client "
           "disconnects " +
           silence + ", or when the car is removed, given a route, the world reset or a map loaded";
  }

  uint32_t timeout_ms_;
  std::map<uint32_t, session::ClientId> drivers_;  // car entity id -> the client driving it
};

}  // namespace sim4cv::daemon
