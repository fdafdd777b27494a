// A daemon safe against bad driving clients (docs/protocol.md, "Bad input";
// docs/protocol.md, "Controls"), on the default scene (car 1 drives its
// lane, heading east, until it gets Controls): Controls with NaN, infinite
// or out-of-range values are refused and never move the car; a car takes
// Controls from one client at a time; and a car whose driver stops sending
// brakes to a stop after --controls-timeout-ms of simulation time.
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

constexpr uint32_t kCarId = 1;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

double Speed(const proto::EntityState& entity) {
  return std::hypot(entity.linear_velocity().x(), entity.linear_velocity().y());
}

void ExpectMentions(const std::string& message, const std::vector<std::string>& parts) {
  for (const std::string& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
  }
}

class ControlsSafetyTest : public ConfigureTest {
 protected:
  // A daemon with `args` and `driver_`, the lockstep client that steps it.
  void Start(std::vector<std::string> args = {}) {
    StartDaemon(std::move(args));
    driver_ = Connect("driver");
    driver_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  }

  // The car after `frames` frames; with `controls` set, the driver sends
  // them before each Step, as a driving policy does.
  proto::EntityState Drive(int frames, const std::vector<float>* controls = nullptr) {
    const proto::Frame* frame = nullptr;
    for (int i = 0; i < frames; ++i) {
      if (controls) driver_->SendControls(kCarId, (*controls)[0], (*controls)[1], (*controls)[2]);
      frame = &driver_->StepAndReceive();
    }
    const proto::EntityState* car = FindEntity(frame->state(), kCarId);
    EXPECT_NE(car, nullptr);
    return car ? *car : proto::EntityState{};
  }

  // Whether `client`'s Controls sent before were taken: a Configure behind
  // them on the same connection is answered after the simulation took them
  // in, so any Error about them has arrived by then.
  static bool ControlsTaken(Client& client) {
    client.GetWorld();
    proto::Envelope envelope;
    if (!client.ReceiveEnvelope(envelope, 100ms)) return true;
    EXPECT_TRUE(envelope.has_error()) << envelope.ShortDebugString();
    return false;
  }

  uint64_t Timeouts() {
    const proto::Stats stats = driver_->GetStats();  // kept: counters() refers into it
    const auto it = stats.counters().find("controls.timeouts");
    return it == stats.counters().end() ? 0 : it->second;
  }

  std::unique_ptr<Client> driver_;
};

TEST_F(ControlsSafetyTest, NanInfiniteAndOutOfRangeControlsAreRefusedAndNeverMoveTheCar) {
  Start();
  // Stop the car with valid Controls: a still car shows any push at once.
  const std::vector<float> full_brake = {0, 0, 1};
  const proto::EntityState stopped = Drive(60, &full_brake);
  ASSERT_LT(Speed(stopped), 0.1) << stopped.ShortDebugString();

  struct Case {
    float steering, throttle, brake;
    std::vector<std::string> parts;  // of the Error's message
  };
  // Each would floor the throttle if it were applied.
  const std::vector<Case> cases = {
      {kNaN, 1, 0, {"Controls.steering is nan; it must be a finite number in [-1, 1]"}},
      {kInf, 1, 0, {"Controls.steering is inf; it must be a finite number in [-1, 1]"}},
      {-kInf, 1, 0, {"Controls.steering is -inf; it must be a finite number in [-1, 1]"}},
      {1.5f, 1, 0, {"Controls.steering is 1.5; it must be a finite number in [-1, 1]"}},
      {0, kNaN, 0, {"Controls.throttle is nan; it must be a finite number in [0, 1]"}},
      {0, kInf, 0, {"Controls.throttle is inf; it must be a finite number in [0, 1]"}},
      {0, 1.5f, 0, {"Controls.throttle is 1.5; it must be a finite number in [0, 1]"}},
      {0, 1, -kInf, {"Controls.brake is -inf; it must be a finite number in [0, 1]"}},
      {0, 1, kNaN, {"Controls.brake is nan; it must be a finite number in [0, 1]"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.parts[0]);
    driver_->SendControls(kCarId, c.steering, c.throttle, c.brake);
    const proto::Error error = NextError(*driver_, proto::ERROR_CODE_INVALID_ARGUMENT);  // non-fatal too
    EXPECT_EQ(error.request_id(), 0u);
    ExpectMentions(error.message(), c.parts);
  }
  // The connection stays open, and the car stands where it stopped.
  const proto::EntityState after = Drive(30);
  EXPECT_LT(Speed(after), 0.1) << after.ShortDebugString();
  EXPECT_LT(PlaneDistance(after.position(), stopped.position()), 0.05) << after.ShortDebugString();
  EXPECT_EQ(driver_->GetState().entities_size(), 2);
}

TEST_F(ControlsSafetyTest, ACarTakesControlsFromOneClientAtATime) {
  Start();
  const std::vector<float> full_brake = {0, 0, 1};
  const proto::EntityState stopped = Drive(60, &full_brake);
  ASSERT_LT(Speed(stopped), 0.1) << stopped.ShortDebugString();

  // Another client's Controls for the driven car: refused, naming the car,
  // the driver and when the car becomes free; its connection stays open.
  auto intruder = Connect("intruder");
  intruder->SendControls(kCarId, 0, 1, 0);
  const proto::Error error = NextError(*intruder, proto::ERROR_CODE_INVALID_STATE);  // non-fatal too
  ExpectMentions(error.message(),
                 {"Controls for car 1 ('car') refused: another client (id " +
                      std::to_string(driver_->welcome().client_id()) + ") drives it",
                  "a car takes Controls from one client at a time",
                  "It becomes free when that client disconnects or sends no Controls for 1000 ms of simulation time "
                  "(--controls-timeout-ms), or when the car is removed, given a route, the world reset or a map "
                  "loaded"});
  EXPECT_EQ(intruder->GetState().entities_size(), 2);
  // The refused throttle never reached the car: the driver's brake holds it.
  const proto::EntityState held = Drive(20, &full_brake);
  EXPECT_LT(Speed(held), 0.1) << held.ShortDebugString();

  // Once the driver is gone (its disconnect reaches the simulation a moment
  // after the close), the intruder's Controls take the car.
  driver_->Close();
  bool taken = false;
  for (int attempt = 0; attempt < 100 && !taken; ++attempt) {
    intruder->SendControls(kCarId, 0, 1, 0);
    taken = ControlsTaken(*intruder);
    if (!taken) std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(taken) << "the car stayed taken after its driver disconnected";
  driver_ = std::move(intruder);
  driver_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  const std::vector<float> full_throttle = {0, 1, 0};
  EXPECT_GT(Speed(Drive(20, &full_throttle)), 1.0) << "the new driver's throttle moves the car";

  // And now the new driver owns it.
  auto third = Connect("third");
  third->SendControls(kCarId, 0, 0, 1);
  ExpectMentions(NextError(*third, proto::ERROR_CODE_INVALID_STATE).message(),
                 {"another client (id " + std::to_string(driver_->welcome().client_id()) + ")"});
}

TEST_F(ControlsSafetyTest, ResetFreesTheCar) {
  Start();
  driver_->SendControls(kCarId, 0, 1, 0);
  ASSERT_TRUE(ControlsTaken(*driver_));
  auto other = Connect("other");
  other->SendControls(kCarId, 0, 1, 0);
  EXPECT_FALSE(ControlsTaken(*other)) << "the driver owns the car";
  driver_->Reset();
  other->SendControls(kCarId, 0, 1, 0);
  EXPECT_TRUE(ControlsTaken(*other)) << "Reset frees every car";
}

TEST_F(ControlsSafetyTest, ACarWhoseDriverStopsSendingBrakesToAStop) {
  Start({"--controls-timeout-ms", "500"});
  const std::vector<float> full_throttle = {0, 1, 0};
  const proto::EntityState driven = Drive(30, &full_throttle);  // 1 s of simulation time
  ASSERT_GT(Speed(driven), 1.0) << driven.ShortDebugString();
  EXPECT_EQ(Timeouts(), 0u);

  // No more Controls: after 0.5 s the car brakes, and 2.5 s stop it.
  const proto::EntityState after = Drive(90);
  EXPECT_LT(Speed(after), 0.1) << after.ShortDebugString();
  EXPECT_EQ(Timeouts(), 1u) << "one timeout, counted once however long the car stands";

  // The car is free: another client's Controls take it.
  auto other = Connect("other");
  other->SendControls(kCarId, 0, 1, 0);
  EXPECT_TRUE(ControlsTaken(*other));
}

TEST_F(ControlsSafetyTest, WithoutATimeoutTheCarKeepsItsLastControls) {
  Start({"--controls-timeout-ms", "0"});
  const std::vector<float> full_throttle = {0, 1, 0};
  const proto::EntityState driven = Drive(30, &full_throttle);
  ASSERT_GT(Speed(driven), 1.0) << driven.ShortDebugString();
  const proto::EntityState after = Drive(90);
  EXPECT_GT(Speed(after), Speed(driven)) << "still on full throttle: " << after.ShortDebugString();
  EXPECT_EQ(Timeouts(), 0u);
  // And the car stays its driver's: the refusal says no silence frees it.
  auto other = Connect("other");
  other->SendControls(kCarId, 0, 0, 1);
  ExpectMentions(NextError(*other, proto::ERROR_CODE_INVALID_STATE).message(),
                 {"when that client disconnects (--controls-timeout-ms is 0: never by silence)"});
}

}  // namespace
}  // namespace sim4cv::testing
