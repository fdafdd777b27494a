// Traffic cars and walkers as the BodyStates that run logs hold for every
// entity, and back: how logging records traffic and replay restores it.
// Positions are on the ground (z = 0), as TrafficState keeps them.
#pragma once

#include "server/sim/state.h"
#include "server/sim/traffic/traffic_state.h"

namespace sim4cv::sim {

BodyState BodyOf(const traffic::MovingCar& car);
BodyState BodyOf(const traffic::Walker& walker);

// Puts a car or walker where `body` says (pose and velocity); the rest of
// its state (lane, route, pauses) is left as it was: replay draws traffic,
// it does not drive it.
void PlaceAt(const BodyState& body, traffic::MovingCar& car);
void PlaceAt(const BodyState& body, traffic::Walker& walker);

}  // namespace sim4cv::sim
