// slamd's startup policy (whiskeye/slamd/startup.h) on scratch state directories: a new map, resuming
// from the newest checkpoint, --fresh, --map refused where it would rotate out another map, a
// checkpoint that cannot be loaded refusing the start, and when a store is opened at all.
#include "whiskeye/slamd/startup.h"

#include "scratch.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace whiskeye::slamd {
namespace {

class SlamdStartup : public ::testing::Test {
 protected:
  std::unique_ptr<slam::VitaSlam> start(const StartupOptions& o, CheckpointStore* store) {
    return start_slam(params_, robot_, o, store, [this](LogLevel level, const std::string& line) {
      log_.push_back(line);
      levels_.push_back(level);
    });
  }
  bool logged(const std::string& text) const {
    for (const std::string& l : log_) {
      if (l.find(text) != std::string::npos) return true;
    }
    return false;
  }
  // A checkpoint of an empty map in `mode`, written into `store`; its path.
  std::string write_map(CheckpointStore& store, uint64_t sequence, slam::Mode mode = slam::Mode::Vita) {
    slam::SlamParams p = params_;
    p.mode = mode;
    return store.write(sequence, slam::VitaSlam(p, robot_).serialise());
  }

  slam::SlamParams params_;
  RobotGeometry robot_ = default_robot_geometry();
  std::vector<std::string> log_;
  std::vector<LogLevel> levels_;
};

TEST_F(SlamdStartup, AnEmptyStateDirectoryStartsANewMap) {
  CheckpointStore store(testing::scratch_dir("startup_empty"), 3);
  auto s = start({}, &store);
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->stats().cycles, 0);
  EXPECT_TRUE(log_.empty());
}

TEST_F(SlamdStartup, ResumesFromTheNewestCheckpoint) {
  CheckpointStore store(testing::scratch_dir("startup_resume"), 3);
  write_map(store, 4);
  const std::string newest = write_map(store, 9);
  auto s = start({}, &store);
  ASSERT_NE(s, nullptr);
  EXPECT_TRUE(logged("resuming from " + newest + " (after cycle 9)"))
      << (log_.empty() ? "" : log_[0]);
  EXPECT_EQ(levels_.at(0), LogLevel::kInfo) << "resuming is progress, not a warning";
}

TEST_F(SlamdStartup, FreshIgnoresTheCheckpointsHeld) {
  CheckpointStore store(testing::scratch_dir("startup_fresh"), 3);
  write_map(store, 9);
  StartupOptions o;
  o.fresh = true;
  ASSERT_NE(start(o, &store), nullptr);
  EXPECT_FALSE(logged("resuming")) << log_[0];
}

TEST_F(SlamdStartup, ACheckpointThatCannotBeLoadedHereRefusesTheStart) {
  CheckpointStore store(testing::scratch_dir("startup_other_mode"), 3);
  write_map(store, 9, slam::Mode::Visual);  // params_ are vita's
  try {
    start({}, &store);
    FAIL() << "started although the newest checkpoint is another mode's map";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot resume from"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--fresh"), std::string::npos) << e.what();
  }
  EXPECT_EQ(store.list().size(), 1u) << "the map is left where it is";
}

TEST_F(SlamdStartup, GrowingAMapIsRefusedWhereItWouldRotateOutAnotherOne) {
  const std::string map_file = testing::scratch_file("startup_map", ".vslam");
  write_checkpoint_file(map_file, 5, slam::VitaSlam(params_, robot_).serialise());
  CheckpointStore store(testing::scratch_dir("startup_map_dir"), 3);
  write_map(store, 9);
  StartupOptions o;
  o.map_file = map_file;
  EXPECT_THROW(start(o, &store), std::runtime_error);
  o.fresh = true;  // the operator lets the held map go
  ASSERT_NE(start(o, &store), nullptr);
  EXPECT_TRUE(logged("loaded map " + map_file + " (0 experiences)"));
  o.fresh = false;
  o.localise = true;  // writes no checkpoints: nothing is rotated out
  auto s = start(o, &store);
  ASSERT_NE(s, nullptr);
  EXPECT_TRUE(s->localise_only());
  EXPECT_TRUE(logged("localising without growing it"));
}

// A loaded map: the robot may be anywhere in it, so slamd starts LOCALISING. A resumed one: only if
// the odometry comes back long after the checkpoint's (the robot may have been moved meanwhile).
TEST_F(SlamdStartup, ALoadedMapLocalisesFirstAndAResumedOneAfterALongGap) {
  params_.mode = slam::Mode::Visual;
  slam::VitaSlam mapped(params_, robot_);
  std::vector<uint8_t> pixels(640 * 480);
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<uint8_t>((i * 7919) % 251);
  const slam::ImageView image{1000000, 640, 480, 640, slam::kPixGrey, pixels};
  const auto cycle_at = [&](int64_t utime) {
    slam::CycleInput in;
    in.utime = utime;
    in.cycle = utime / 1000000;
    in.image = &image;
    in.odometry = {{utime, 0.1, 0.0, 0.0}};
    return in;
  };
  mapped.process_cycle(cycle_at(1000000));
  ASSERT_EQ(mapped.map().size(), 1);
  const std::string map_file = testing::scratch_file("startup_localise", ".vslam");
  write_checkpoint_file(map_file, 1, mapped.serialise());
  StartupOptions o;
  o.map_file = map_file;
  o.localise = true;
  auto loaded = start(o, nullptr);
  ASSERT_NE(loaded, nullptr);
  EXPECT_TRUE(loaded->localiser().localising());

  CheckpointStore store(testing::scratch_dir("startup_resume_gap"), 3);
  store.write(1, mapped.serialise());
  auto quick = start({}, &store);
  EXPECT_FALSE(quick->process_cycle(cycle_at(2000000)).localising);  // odometry 1 s on: tracking
  auto later = start({}, &store);
  const slam::CycleResult r = later->process_cycle(cycle_at(100000000));  // 99 s on
  EXPECT_TRUE(r.localising || later->localiser().localisations() == 1);
}

TEST_F(SlamdStartup, NoStoreWithLocaliseOrWithoutADirectory) {
  std::optional<CheckpointStore> store;
  open_store(store, testing::scratch_dir("startup_store"), 3, /*localise=*/true);
  EXPECT_FALSE(store.has_value());
  open_store(store, "", 3, false);
  EXPECT_FALSE(store.has_value());
  open_store(store, testing::scratch_dir("startup_store2"), 3, false);
  EXPECT_TRUE(store.has_value());
}

TEST_F(SlamdStartup, LiveStateDirectoryIsTheOptionThenSystemdsThenVarLib) {
  EXPECT_EQ(live_state_directory("/tmp/given"), "/tmp/given");
  ::setenv("STATE_DIRECTORY", "/run/state", 1);
  EXPECT_EQ(live_state_directory(""), "/run/state");
  ::unsetenv("STATE_DIRECTORY");
  EXPECT_EQ(live_state_directory(""), "/var/lib/slamd");
}

}  // namespace
}  // namespace whiskeye::slamd
