// The paper's central claim (Table I) end to end on the default aliased arena, through the real
// executables: vita-sim writes a log, slamd --replay processes it in the three modes, vita-eval
// scores them. Vision alone and touch alone are fooled by the aliasing (false loop closures, a
// distorted map); their fusion re-localises only correctly and keeps the map consistent.
#include "subprocess.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

namespace whiskeye {
namespace {

namespace fs = std::filesystem;
using testing::Subprocess;

void run(const std::vector<std::string>& argv, double timeout_s) {
  Subprocess p(argv);
  const int rc = p.wait(timeout_s);
  ASSERT_EQ(rc, 0) << argv[0] << " failed (" << rc << "):\n" << p.output();
}

using Runs = std::map<std::string, nlohmann::json>;

// slamd --replay of `sim_log` in the three modes with the shipped config and `sets` (--set K=V),
// scored by vita-eval: the runs by mode.
Runs replay_and_score(const fs::path& dir, const std::string& sim_log, const std::vector<std::string>& sets) {
  const std::string src = WHISKEYE_SOURCE_DIR;
  fs::create_directories(dir);
  std::vector<std::string> eval{VITA_EVAL_EXE, "--json", (dir / "metrics.json").string()};
  for (const std::string mode : {"visual", "tactile", "vita"}) {
    const std::string out = (dir / ("slam-" + mode + ".lcmlog")).string();
    std::vector<std::string> argv{SLAMD_EXE, "--replay", sim_log, "--output", out, "--mode", mode, "--config",
                                  src + "/config/slam.yaml", "--robot", src + "/config/robot.yaml"};
    for (const std::string& kv : sets) argv.insert(argv.end(), {"--set", kv});
    run(argv, 300);
    eval.insert(eval.end(), {"--input", out});
  }
  run(eval, 300);
  std::ifstream f(dir / "metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(f);
  Runs by_mode;
  for (const auto& r : metrics.at("runs")) by_mode[r.at("mode").get<std::string>()] = r;
  return by_mode;
}

double arcr(const nlohmann::json& r) { return r.at("exm").at("arcr").get<double>(); }
double arr(const nlohmann::json& r) { return r.at("exm").at("arr").get<double>(); }
double enm(const nlohmann::json& r) { return r.at("enm").at("enm").get<double>(); }
double lem(const nlohmann::json& r) { return r.at("lem").at("position_m").at("rmse").get<double>(); }
int false_closures(const nlohmann::json& r) { return r.at("exm").at("false_closures").get<int>(); }

// One simulator log of the default arena (seed 2), replayed with the paper's scheme and with the
// shipped parameters.
TEST(TableOne, FusionRemovesTheFalseLoopClosuresThatFoolVisionAndTouch) {
  const fs::path dir = fs::temp_directory_path() / ("table_one_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string src = WHISKEYE_SOURCE_DIR;
  const std::string sim_log = (dir / "sim.lcmlog").string();
  ASSERT_NO_FATAL_FAILURE(run({VITA_SIM_EXE, "--world", src + "/config/worlds/aliased_arena.yaml", "--robot",
                               src + "/config/robot.yaml", "--seed", "2", "--output", sim_log, "-q"},
                              300));
  const std::vector<std::string> paper_scheme{"slam.experience_map.drift_per_m=1000", "slam.match.tactile_veto=0"};
  Runs paper = replay_and_score(dir / "paper", sim_log, paper_scheme);
  ASSERT_FALSE(HasFatalFailure());
  Runs shipped = replay_and_score(dir / "shipped", sim_log, {});
  ASSERT_FALSE(HasFatalFailure());
  fs::remove(sim_log);  // ~1 GB
  ASSERT_EQ(paper.size(), 3u);
  ASSERT_EQ(shipped.size(), 3u);

  // The paper's scheme (the pose cells alone decide a closure, ε summed): Table I's claim.
  // Fusion: every loop closure correct, and many of them; the map is metrically right.
  EXPECT_EQ(arcr(paper["vita"]), 1.0);
  EXPECT_EQ(false_closures(paper["vita"]), 0);
  EXPECT_GE(arr(paper["vita"]), 0.75);
  EXPECT_LE(lem(paper["vita"]), 0.10);
  // Its map's energy is an order of magnitude below either single sense's (measured: 31× below
  // touch's and 2,900× below vision's on this seed; ARR 0.785).
  EXPECT_LE(enm(paper["vita"]), enm(paper["tactile"]) / 10);
  EXPECT_LE(enm(paper["vita"]), enm(paper["visual"]) / 10);
  // Each sense alone is fooled: touch re-localises on the wrong identical box almost always,
  // vision on the wrong striped landmark for a large part of every lap; both maps are distorted.
  EXPECT_LE(arcr(paper["tactile"]), 0.5);
  EXPECT_LE(arcr(paper["visual"]), 0.8);
  EXPECT_GT(false_closures(paper["visual"]), 10);
  EXPECT_GT(lem(paper["visual"]), 0.5);
  EXPECT_GT(lem(paper["tactile"]), 0.2);

  // The shipped parameters (the odometry-consistency gate; touch vetoes, vision chooses): the fusion
  // makes no false closure, re-localises at least as often, and is never worse than its best sense.
  const nlohmann::json& vita = shipped["vita"];
  EXPECT_EQ(false_closures(vita), 0);
  EXPECT_GE(arcr(vita), 0.98);
  EXPECT_GE(arr(vita), 0.75);
  EXPECT_LE(lem(vita), 0.10);
  EXPECT_LE(lem(vita), std::min(lem(shipped["visual"]), lem(shipped["tactile"])) + 0.03);
  EXPECT_GE(arr(vita), arr(shipped["visual"]));
  // Vision alone is no longer fooled here (the gate: a look-alike place is farther than odometry
  // can have drifted); touch alone still is, closer by (its twin boxes are within reach).
  EXPECT_EQ(false_closures(shipped["visual"]), 0);
  EXPECT_LE(arcr(shipped["tactile"]), 0.5);
  fs::remove_all(dir);
}

// The quick version of the suite's kidnap scenario (scripts/demo-kidnap's kidnap and seed), with
// kidnap detection on (off as shipped: docs/results.md): the default arena mapped for 2.5 laps, the
// robot put down 45° back along its path at 160 s while odometry goes on. The fusion reports
// LOCALISING, localises within a lap and takes no false localisation on the way; touch alone,
// aliased by design, never finds the place again.
TEST(Kidnap, TheFusionLocalisesAfterAKidnapOnTheDefaultArenaWithoutAFalseLocalisation) {
  const fs::path dir = fs::temp_directory_path() / ("kidnap_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string src = WHISKEYE_SOURCE_DIR;
  const std::string world = (dir / "arena-kidnap.yaml").string();
  {
    std::ifstream arena(src + "/config/worlds/aliased_arena.yaml");
    std::ofstream out(world);
    out << arena.rdbuf() << "  faults:\n    kidnap: [{at: 160.0, to_angle: 0.3}]\n";
  }
  const std::string sim_log = (dir / "sim.lcmlog").string();
  ASSERT_NO_FATAL_FAILURE(
      run({VITA_SIM_EXE, "--world", world, "--robot", src + "/config/robot.yaml", "--seed", "1", "--output", sim_log, "-q"},
          300));
  Runs runs = replay_and_score(dir / "detect", sim_log, {"slam.localisation.kidnap_disagreements=4"});
  ASSERT_FALSE(HasFatalFailure());
  fs::remove(sim_log);
  ASSERT_EQ(runs.size(), 3u);
  const auto kidnap = [&](const std::string& mode) {
    const nlohmann::json& l = runs[mode].at("localisation");
    EXPECT_EQ(l.at("instants").size(), 1u) << mode;
    return l.at("instants").at(0);
  };
  const nlohmann::json vita = kidnap("vita");
  EXPECT_EQ(vita.at("kind"), "kidnap");
  EXPECT_TRUE(vita.at("localised").get<bool>());
  EXPECT_LE(vita.at("laps_to_localise").get<double>(), 1.0);
  EXPECT_EQ(vita.at("false_localisations").get<int>(), 0) << vita.dump();
  EXPECT_GT(vita.at("localising_s").get<double>(), 0.0) << "slamd said it did not know where it was";
  EXPECT_LE(vita.at("lem_after_m").get<double>(), 0.10);
  const nlohmann::json touch = kidnap("tactile");
  EXPECT_TRUE(!touch.at("localised").get<bool>() || touch.at("false_localisations").get<int>() > 0) << touch.dump();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace whiskeye
