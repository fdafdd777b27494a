// A lockstep client that attaches over shared memory to a ring that already
// holds frames (another client stepped the world first) gets, for each of
// its Steps, the frame that Step made: the ring's existing newest frame is
// not the answer to its first Step. The Octave/MATLAB client goes through
// this same C++ client.
#include "tests/integration/shm_fixture.h"

namespace sim4cv::testing {
namespace {

TEST_F(ShmDaemonTest, TheFirstStepAfterAttachingToAFilledRingGetsItsOwnFrame) {
  StartShmDaemon();
  {
    auto before = Connect("before");
    before->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
    for (int i = 0; i < 10; ++i) before->StepAndReceive();
  }  // the ring now holds frames up to 10
  Client shm;
  shm.Connect("shm://" + shm_name_, "late");
  shm.Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  for (uint64_t step = 1; step <= 3; ++step) {
    const proto::Frame& frame = shm.StepAndReceive();
    const uint64_t world = shm.GetState().frame_id();
    EXPECT_EQ(frame.frame_id(), world) << "Step " << step << " got frame " << frame.frame_id()
                                       << " while the world is at " << world;
    EXPECT_EQ(frame.frame_id(), 10 + step);
  }
}

}  // namespace
}  // namespace sim4cv::testing
