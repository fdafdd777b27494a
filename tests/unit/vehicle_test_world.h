// A Bullet world for the vehicle tests: z up, gravity -9.81, a ground plane
// at z = 0, stepped at the daemon's fixed 240 Hz with exactly one substep.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <cmath>

namespace sim4cv::vehicles::testing {

constexpr double kDt = 1.0 / 240.0;

inline int Steps(double seconds) { return static_cast<int>(std::lround(seconds / kDt)); }

struct TestWorld {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  btStaticPlaneShape ground_shape{btVector3(0, 0, 1), 0};
  btRigidBody ground{0, nullptr, &ground_shape};

  TestWorld() {
    world.setGravity(btVector3(0, 0, -9.81));
    world.addRigidBody(&ground);
  }
  ~TestWorld() { world.removeRigidBody(&ground); }
  TestWorld(const TestWorld&) = delete;
  TestWorld& operator=(const TestWorld&) = delete;

  void Step() { world.stepSimulation(btScalar(kDt), 0); }
};

}  // namespace sim4cv::vehicles::testing
