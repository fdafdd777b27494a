// Helpers shared by the integration tests of Configure (configure_*_test.cpp):
// a daemon that must log no warning, lockstep stepping, and lookups in the
// State, WorldInfo and Frame messages the daemon sends back.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <initializer_list>
#include <optional>
#include <string>

#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {

class ConfigureTest : public DaemonTest {
 protected:
  // Besides DaemonTest's checks: the daemon logged no warning and no error
  // (refused Configures are logged at info level).
  void TearDown() override {
    DaemonTest::TearDown();
    if (daemon_) {
      for (const std::string& line : daemon_->warning_lines()) ADD_FAILURE() << "sim4cvd logged: " << line;
    }
  }

  // Steps `client` (subscribed in lockstep) `frames` times; the last frame.
  static const proto::Frame& StepFrames(Client& client, int frames) {
    for (int i = 1; i < frames; ++i) client.StepAndReceive();
    return client.StepAndReceive();
  }

  // `call` must throw a ServerError with `code` whose message holds every one of `parts`.
  static void ExpectRefused(const std::function<void()>& call, proto::ErrorCode code,
                            std::initializer_list<std::string> parts) {
    try {
      call();
      ADD_FAILURE() << "expected " << proto::ErrorCode_Name(code) << ", but the request was carried out";
    } catch (const ServerError& error) {
      EXPECT_EQ(error.code(), code) << error.what();
      EXPECT_FALSE(error.fatal()) << error.what();
      EXPECT_NE(error.request_id(), 0u) << "a Configure's Error echoes its request_id: " << error.what();
      for (const std::string& part : parts) {
        EXPECT_NE(std::string(error.what()).find(part), std::string::npos) << "'" << part << "' not in: " << error.what();
      }
    }
  }

  // Reads the next envelope off `client`: it must be an Error with `code`.
  static proto::Error NextError(Client& client, proto::ErrorCode code) {
    proto::Envelope envelope;
    EXPECT_TRUE(client.ReceiveEnvelope(envelope, std::chrono::milliseconds(10000))) << "no reply within 10 s";
    EXPECT_TRUE(envelope.has_error()) << envelope.ShortDebugString();
    EXPECT_EQ(envelope.error().code(), code) << envelope.error().message();
    EXPECT_FALSE(envelope.error().fatal()) << envelope.error().message();
    return envelope.error();
  }
};

// The entity with `id` in `state`, or nullptr.
inline const proto::EntityState* FindEntity(const proto::State& state, uint32_t id) {
  for (const auto& entity : state.entities()) {
    if (entity.id() == id) return &entity;
  }
  return nullptr;
}

// The entity called `name` in `world`, or nullptr.
inline const proto::EntityInfo* FindEntity(const proto::WorldInfo& world, const std::string& name) {
  for (const auto& entity : world.entities()) {
    if (entity.name() == name) return &entity;
  }
  return nullptr;
}

inline bool HasCamera(const proto::WorldInfo& world, const std::string& name) {
  for (const auto& camera : world.cameras()) {
    if (camera.name() == name) return true;
  }
  return false;
}

// The Box of `object_id` in `frame` (subscribed with CHANNEL_BOXES), if visible.
inline std::optional<proto::Box> BoxOf(const proto::Frame& frame, uint32_t object_id) {
  for (const auto& box : frame.boxes()) {
    if (box.object_id() == object_id) return box;
  }
  return std::nullopt;
}

inline proto::Vec3 Vec(double x, double y, double z) {
  proto::Vec3 v;
  v.set_x(x);
  v.set_y(y);
  v.set_z(z);
  return v;
}

// Horizontal distance between two points.
inline double PlaneDistance(const proto::Vec3& a, const proto::Vec3& b) { return std::hypot(a.x() - b.x(), a.y() - b.y()); }

inline double Distance(const proto::Vec3& a, const proto::Vec3& b) {
  return std::sqrt(std::pow(a.x() - b.x(), 2) + std::pow(a.y() - b.y(), 2) + std::pow(a.z() - b.z(), 2));
}

}  // namespace sim4cv::testing
