// Simulation::Apply, the sim thread's side of Configure, without a daemon:
// what each request changes, what it reports, and the Error it throws.
#include "server/daemon/simulation.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "tests/support/no_warnings.h"

namespace sim4cv::daemon {
namespace {

class SimulationTest : public ::testing::Test {
 protected:
  Simulation::Change Apply(const proto::Configure& request) { return sim_.Apply(request, answer_); }

  // Applying `request` throws a ConfigureError with `code` whose message holds `part`.
  void ExpectRefused(const proto::Configure& request, proto::ErrorCode code, const std::string& part) {
    try {
      Apply(request);
      ADD_FAILURE() << "accepted: " << request.ShortDebugString();
    } catch (const ConfigureError& error) {
      EXPECT_EQ(error.code(), code) << error.what();
      EXPECT_NE(std::string(error.what()).find(part), std::string::npos) << error.what();
    }
  }

  Config config_;
  Simulation sim_{config_, std::make_shared<const sim::Scene>(sim::DefaultScene(320, 180))};
  proto::Configured answer_;
};

proto::Configure SpawnUav(const std::string& name) {
  proto::Configure request;
  request.set_request_id(5);
  request.mutable_spawn()->set_kind(proto::ENTITY_KIND_UAV);
  request.mutable_spawn()->set_name(name);
  request.mutable_spawn()->mutable_position()->set_z(10);
  return request;
}

proto::Configure AddCamera(const std::string& name, const std::string& mount) {
  proto::Configure request;
  proto::AddCamera& camera = *request.mutable_add_camera();
  camera.set_name(name);
  camera.set_mounted_on(mount);
  camera.set_width(160);
  camera.set_height(120);
  camera.set_fov_y_deg(70);
  return request;
}

TEST_F(SimulationTest, SetConditionsChangesTheLookAndReportsItInTheWorld) {
  proto::Configure request;
  request.mutable_set_conditions()->set_preset("dusk");
  const Simulation::Change change = Apply(request);
  EXPECT_TRUE(change.new_conditions);
  EXPECT_FALSE(change.new_scene);
  EXPECT_EQ(sim_.conditions().preset, conditions::Preset::DUSK);
  EXPECT_EQ(answer_.world().conditions().preset(), "dusk");
  EXPECT_EQ(answer_.world().conditions().hour(), conditions::Info(conditions::Preset::DUSK).hour);
  EXPECT_EQ(answer_.world().conditions().quality(), "full");
  // Only the hour: the preset stays.
  request.mutable_set_conditions()->clear_preset();
  request.mutable_set_conditions()->set_hour(6.25);
  request.mutable_set_conditions()->set_quality("fast");
  Apply(request);
  EXPECT_EQ(answer_.world().conditions().preset(), "dusk");
  EXPECT_EQ(answer_.world().conditions().hour(), 6.25);
  EXPECT_EQ(answer_.world().conditions().quality(), "fast");
}

TEST_F(SimulationTest, SetConditionsIsRefusedWhileLogging) {
  Config logging;
  logging.log_file = "/tmp/never-written.s4log";  // Simulation only reads the flag
  Simulation sim(logging, std::make_shared<const sim::Scene>(sim::DefaultScene(320, 180)));
  proto::Configure request;
  request.mutable_set_conditions()->set_preset("night");
  try {
    sim.Apply(request, answer_);
    ADD_FAILURE() << "accepted while logging";
  } catch (const ConfigureError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_INVALID_STATE);
    EXPECT_NE(std::string(error.what()).find("a log holds one look"), std::string::npos) << error.what();
  }
  EXPECT_EQ(sim.conditions().preset, conditions::Preset::CLEAR_NOON);
}

TEST_F(SimulationTest, RandomisationDrawsPerEpisodeOrEveryNFramesFromItsSeed) {
  Config per_episode;
  per_episode.randomize_seed = 11;
  Simulation sim(per_episode, std::make_shared<const sim::Scene>(sim::DefaultScene(320, 180)));
  const auto same = [](const conditions::Conditions& a, const conditions::Conditions& b) {
    return a.preset == b.preset && a.hour == b.hour && a.exposure == b.exposure && a.variation == b.variation;
  };
  EXPECT_TRUE(same(sim.conditions(), conditions::Randomized(11, 0, conditions::Conditions{})));
  EXPECT_FALSE(sim.AdvanceConditions()) << "per episode: frames do not draw";
  proto::Configure reset;
  reset.mutable_reset();
  EXPECT_TRUE(sim.Apply(reset, answer_).new_conditions);
  EXPECT_TRUE(same(sim.conditions(), conditions::Randomized(11, 1, conditions::Conditions{})));
  EXPECT_EQ(answer_.world().conditions().randomize_seed(), 11u);
  EXPECT_EQ(answer_.world().conditions().variation(), conditions::Randomized(11, 1, conditions::Conditions{}).variation);

  // Every 5 frames, through SetConditions.
  proto::Configure every;
  every.mutable_set_conditions()->set_randomize_seed(11);
  every.mutable_set_conditions()->set_randomize_every_frames(5);
  sim.Apply(every, answer_);
  sim.state().frame_id = 9;
  EXPECT_FALSE(sim.AdvanceConditions());
  sim.state().frame_id = 10;
  EXPECT_TRUE(sim.AdvanceConditions());
  EXPECT_TRUE(same(sim.conditions(), conditions::Randomized(11, 2, conditions::Conditions{})));
  // An explicit preset stops it.
  proto::Configure fixed;
  fixed.mutable_set_conditions()->set_preset("fog");
  sim.Apply(fixed, answer_);
  sim.state().frame_id = 15;
  EXPECT_FALSE(sim.AdvanceConditions());
  EXPECT_EQ(sim.conditions().preset, conditions::Preset::FOG);
  EXPECT_EQ(answer_.world().conditions().randomize_seed(), 0u);
}

TEST_F(SimulationTest, SpawnAnswersTheIdAndTheWorld) {
  Apply(SpawnUav("scout"));
  EXPECT_EQ(answer_.request_id(), 5u);
  EXPECT_EQ(answer_.entity_id(), 3u);
  ASSERT_EQ(answer_.world().entities_size(), 3);
  EXPECT_EQ(answer_.world().entities(2).name(), "scout");
  EXPECT_EQ(answer_.world().scene_name(), "default");
  ExpectRefused(SpawnUav("scout"), proto::ERROR_CODE_INVALID_ARGUMENT, "'scout' already exists");
}

TEST_F(SimulationTest, RemovingAnEntityRemovesItsCamerasAndReportsThem) {
  Apply(SpawnUav("scout"));
  Apply(AddCamera("left", "scout"));
  Apply(AddCamera("right", "scout"));
  EXPECT_EQ(sim_.FindCamera("right"), 4);
  proto::Configure remove;
  remove.mutable_remove()->set_entity_id(3);
  const Simulation::Change change = Apply(remove);
  EXPECT_EQ(change.removed_cameras, (std::vector<uint32_t>{3, 4}));
  EXPECT_EQ(sim_.FindCamera("left"), -1);
  ASSERT_EQ(sim_.cameras().size(), 5u) << "removed cameras keep their indices";
  EXPECT_TRUE(sim_.cameras()[3].name.empty());
  ExpectRefused(remove, proto::ERROR_CODE_UNKNOWN_ENTITY, "no entity has id 3");
  ExpectRefused(AddCamera("up", "nobody"), proto::ERROR_CODE_UNKNOWN_ENTITY, "no entity is named 'nobody'");
}

TEST_F(SimulationTest, ResetRestoresTheSceneAndDropsWhatClientsAdded) {
  Apply(SpawnUav("scout"));
  Apply(AddCamera("fixed", ""));
  for (int i = 0; i < 100; ++i) sim_.world().Step(sim_.state(), 1.0 / 240);
  proto::Configure reset;
  reset.mutable_reset();
  EXPECT_TRUE(Apply(reset).new_scene);
  EXPECT_EQ(sim_.state().entities.size(), 2u);
  EXPECT_EQ(sim_.state().physics_steps, 0u);
  EXPECT_EQ(sim_.cameras().size(), 3u);
}

TEST_F(SimulationTest, AMapTextWithAnErrorIsRefusedNamingTheLineAndChangesNothing) {
  proto::Configure load;
  load.mutable_load_map()->set_text("sim4cv-map 1\nname bad\ncolour red\n");
  ExpectRefused(load, proto::ERROR_CODE_INVALID_ARGUMENT, "line 3");
  EXPECT_EQ(sim_.scene().name, "default");
  proto::Configure query;
  query.mutable_query_road();
  ExpectRefused(query, proto::ERROR_CODE_INVALID_STATE, "needs a map scene");
}

TEST_F(SimulationTest, AShippedMapLoadsByNameAndAnswersRoadQueries) {
  proto::Configure load;
  load.mutable_load_map()->set_name("tracking/easy_urban");
  EXPECT_TRUE(Apply(load).new_scene);
  EXPECT_EQ(sim_.scene().name, answer_.world().scene_name());
  ASSERT_GT(answer_.world().routes_size(), 0);
  proto::Configure query;
  const Eigen::Vector3d car = sim_.state().Find(sim::kCarEntityId)->body.position;
  query.mutable_query_road()->mutable_point()->set_x(car.x());
  query.mutable_query_road()->mutable_point()->set_y(car.y());
  query.mutable_query_road()->set_count(4);
  query.mutable_query_road()->set_step(2);
  Apply(query);
  EXPECT_LT(answer_.road().distance(), 0.1) << "the car starts on its lane";
  EXPECT_EQ(answer_.road().ahead_size(), 4);
}

// The sim thread undoes a carried-out request whose graphics it cannot
// build: the world is then exactly the one before it.
TEST_F(SimulationTest, UndoPutsBackTheWorldALoadMapOrAddCameraReplaced) {
  Apply(SpawnUav("scout"));
  const std::size_t entities = sim_.state().entities.size();
  const std::size_t cameras = sim_.cameras().size();
  proto::Configure load;
  load.mutable_load_map()->set_name("tracking/easy_urban");
  EXPECT_TRUE(Apply(load).new_scene);
  EXPECT_NE(sim_.scene().name, "default");
  sim_.Undo();
  EXPECT_EQ(sim_.scene().name, "default");
  EXPECT_EQ(sim_.state().entities.size(), entities);
  EXPECT_NE(sim_.state().FindByName("scout"), nullptr);
  EXPECT_EQ(sim_.cameras().size(), cameras);
  sim_.world().Step(sim_.state(), 1.0 / 240);  // the old World is whole again

  Apply(AddCamera("fixed", ""));
  EXPECT_EQ(sim_.cameras().size(), cameras + 1);
  sim_.Undo();
  EXPECT_EQ(sim_.cameras().size(), cameras);
  Apply(AddCamera("fixed", ""));
  sim_.Commit();
  sim_.Undo();  // nothing left to undo once committed
  EXPECT_EQ(sim_.cameras().size(), cameras + 1);
}

}  // namespace
}  // namespace sim4cv::daemon
