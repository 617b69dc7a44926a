// The real slamd binary on a short simulator run: deterministic replay, checkpoints and resume,
// reuse of a saved map, bad configuration, and a live run fed by lcm-logplayer over udpm:// (inside
// a private network namespace) that takes the same decisions as --replay.
#include "whiskeye/slamd/checkpoint_store.h"
#include "slamd_files.h"
#include "subprocess.h"

#include "whiskeye/common/bus.h"

#include <whiskeye/odometry_t.hpp>
#include <whiskeye/slam_status_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <thread>
#include <unistd.h>

namespace whiskeye {
namespace {

namespace fs = std::filesystem;
using testing::checkpoint_files;
using testing::read_slamd_output;
using testing::SlamdOutput;
using testing::Subprocess;
using testing::wait_until;
using ::testing::HasSubstr;
using ::testing::Not;

const std::string kSlamd = SLAMD_EXE;
const std::string kConfig = WHISKEYE_SOURCE_DIR "/config/slam.yaml";

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class SlamdBinary : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // ctest runs each test in its own process, concurrently: one directory per process.
    dir_ = fs::path(::testing::TempDir()) / ("slamd_binary_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    sim_log_ = (dir_ / "sim.lcmlog").string();
    Subprocess sim({VITA_SIM_EXE, "--world", WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml", "--robot",
                    WHISKEYE_SOURCE_DIR "/config/robot.yaml", "--duration", "14", "--seed", "5", "--quiet",
                    "--output", sim_log_});
    ASSERT_EQ(sim.wait(120), 0) << sim.output();
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static int replay(const std::string& out, std::vector<std::string> extra = {}, std::string* log = nullptr) {
    std::vector<std::string> argv{kSlamd, "--replay", sim_log_, "--output", out, "--config", kConfig};
    argv.insert(argv.end(), extra.begin(), extra.end());
    Subprocess p(argv);
    const int rc = p.wait(120);
    if (log) *log = p.output();
    return rc;
  }

  // An empty directory `name` in the test's directory (a state directory of its own).
  static fs::path fresh_dir(const std::string& name) {
    const fs::path path = dir_ / name;
    fs::remove_all(path);
    return path;
  }
  // Whether a live slamd says, within 20 s, that it runs.
  static bool started(const Subprocess& slamd) {
    return wait_until([&] { return slamd.output().find("running in vita mode") != std::string::npos; }, 20);
  }

  static fs::path dir_;
  static std::string sim_log_;
};
fs::path SlamdBinary::dir_;
std::string SlamdBinary::sim_log_;

TEST_F(SlamdBinary, ReplayIsByteIdenticalAndCopiesGroundTruth) {
  const std::string a = (dir_ / "a.lcmlog").string();
  const std::string b = (dir_ / "b.lcmlog").string();
  std::string log;
  ASSERT_EQ(replay(a, {}, &log), 0) << log;
  EXPECT_THAT(log, HasSubstr("replayed"));
  ASSERT_EQ(replay(b), 0);
  EXPECT_EQ(slurp(a), slurp(b));
  const SlamdOutput o = read_slamd_output(a);
  EXPECT_GE(o.events.size(), 12u) << "one event per whisk cycle (14 s of whisking at 1 Hz)";
  EXPECT_EQ(o.events.front().type, vita_event_t::NEW_EXPERIENCE);
  EXPECT_GE(o.ground_truth, 14 * 50 - 5) << "GROUND_TRUTH (50 Hz) is copied through for vita-eval";
  ASSERT_FALSE(o.maps.empty());
  EXPECT_GE(o.maps.back().num_experiences, 2);
}

TEST_F(SlamdBinary, TruncatedLogIsReplayedUpToTheBreakThenFailsNamingIt) {
  const std::string cut = (dir_ / "cut.lcmlog").string();
  const std::string full = slurp(sim_log_);
  std::ofstream(cut, std::ios::binary).write(full.data(), static_cast<std::streamsize>(full.size() * 2 / 3));
  const std::string out = (dir_ / "cut_out.lcmlog").string();
  std::vector<std::string> argv{kSlamd, "--replay", cut, "--output", out, "--config", kConfig};
  Subprocess p(argv);
  EXPECT_EQ(p.wait(120), 1);
  EXPECT_THAT(p.output(), HasSubstr(cut + ": truncated LCM log: the event at byte "));
  const SlamdOutput o = read_slamd_output(out);
  EXPECT_GE(o.events.size(), 6u) << "the cycles before the break were processed";
  ASSERT_FALSE(o.maps.empty()) << "and the final map written";
}

// The back end's test instrument: a wrong closure for every closure, said on the last line; refused
// without --replay and for a kind it does not know.
TEST_F(SlamdBinary, InjectsWrongClosuresIntoAReplayOnlyAndSaysHowMany) {
  const std::string out = (dir_ / "injected.lcmlog").string();
  std::string log;
  ASSERT_EQ(replay(out, {"--inject-wrong-closures", "random", "--inject-seed", "3"}, &log), 0) << log;
  EXPECT_THAT(log, HasSubstr("slamd: injected "));
  EXPECT_THAT(log, HasSubstr(" wrong closures (random, seed 3)"));
  Subprocess live({kSlamd, "--config", kConfig, "--inject-wrong-closures", "random"});
  EXPECT_EQ(live.wait(30), 2);
  EXPECT_THAT(live.output(), HasSubstr("--replay"));
  std::string bad;
  EXPECT_EQ(replay(out, {"--inject-wrong-closures", "everywhere"}, &bad), 2);
  EXPECT_THAT(bad, HasSubstr("--inject-wrong-closures"));
}

TEST_F(SlamdBinary, ModesDifferInWhatTheyCompare) {
  for (const std::string mode : {"visual", "tactile"}) {
    const std::string out = (dir_ / ("mode_" + mode + ".lcmlog")).string();
    ASSERT_EQ(replay(out, {"--mode", mode}), 0);
    const SlamdOutput o = read_slamd_output(out);
    ASSERT_FALSE(o.events.empty());
    EXPECT_EQ(o.events.front().mode, mode == "visual" ? 0 : 1);
  }
}

TEST_F(SlamdBinary, CheckpointsAndResumesSkippingACorruptOne) {
  const fs::path state = fresh_dir("state");
  ASSERT_EQ(replay((dir_ / "cp1.lcmlog").string(), {"--state-dir", state.string(), "--checkpoint-keep", "2"}), 0);
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(state)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 2u) << "the newest two are kept";
  // Corrupt the newest: the next start must name it and resume from the other.
  {
    std::fstream f(files.back(), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100);
    f.put('\x7f');
  }
  std::string log;
  ASSERT_EQ(replay((dir_ / "cp2.lcmlog").string(), {"--state-dir", state.string()}, &log), 0) << log;
  EXPECT_THAT(log, HasSubstr("skipped unusable checkpoint " + files.back().string()));
  EXPECT_THAT(log, HasSubstr("resuming from " + files.front().string()));
  EXPECT_TRUE(fs::exists(files.back().string() + ".corrupt"));
}

// The cycles after the last periodic checkpoint are saved at the end of a replay, as live slamd
// saves them on SIGTERM.
TEST_F(SlamdBinary, AReplaySavesItsFinalStateWhateverTheCheckpointPeriod) {
  const fs::path state = fresh_dir("final_state");
  std::string log;
  ASSERT_EQ(replay((dir_ / "final.lcmlog").string(), {"--state-dir", state.string(), "--checkpoint-every", "5"}, &log),
            0)
      << log;
  const auto files = checkpoint_files(state);
  ASSERT_FALSE(files.empty());
  std::smatch m;
  ASSERT_TRUE(std::regex_search(log, m, std::regex(R"(of data in .*: (\d+) cycles)"))) << log;
  const uint64_t replayed = std::stoull(m[1]);
  ASSERT_NE(replayed % 5, 0u) << "the log must end between two periodic checkpoints";
  EXPECT_EQ(slamd::read_checkpoint(files.back().string()).sequence, replayed)
      << "the newest checkpoint is the final state, not the last multiple of 5";
}

// A replay by hand pointed at the state directory of a running slamd: refused, naming it, and the
// running one's map is untouched.
TEST_F(SlamdBinary, ASecondSlamdOnTheSameStateDirectoryIsRefused) {
  const fs::path state = fresh_dir("shared_state");
  Subprocess live({kSlamd, "--config", kConfig, "--state-dir", state.string()});
  ASSERT_TRUE(started(live)) << live.output();
  std::string log;
  EXPECT_EQ(replay((dir_ / "second.lcmlog").string(), {"--state-dir", state.string(), "--mode", "tactile"}, &log), 1);
  EXPECT_THAT(log, HasSubstr(state.string() + ": in use by another slamd"));
  EXPECT_TRUE(checkpoint_files(state).empty()) << "the refused replay wrote nothing";
  live.signal(SIGTERM);
  EXPECT_EQ(live.wait(30), 0) << live.output();
  ASSERT_EQ(checkpoint_files(state).size(), 1u) << "the live one's final checkpoint";
  // With the directory free again, the same replay resumes from it (same mode) and runs.
  EXPECT_EQ(replay((dir_ / "third.lcmlog").string(), {"--state-dir", state.string()}, &log), 0) << log;
  EXPECT_THAT(log, HasSubstr("resuming from "));
}

TEST_F(SlamdBinary, EverySessionResumesFromThePreviousOneAndFreshStartsANewMap) {
  const fs::path state = fresh_dir("sessions");
  const std::vector<std::string> args{"--state-dir", state.string(), "--checkpoint-keep", "2"};
  std::string log;
  ASSERT_EQ(replay((dir_ / "s1.lcmlog").string(), args, &log), 0) << log;
  EXPECT_THAT(log, Not(HasSubstr("resuming")));
  const std::size_t cycles = read_slamd_output((dir_ / "s1.lcmlog").string()).events.size();
  ASSERT_GT(cycles, 0u);
  // Each session goes on from the state the previous one left: its own checkpoints must not be
  // rotated out by the older, higher-numbered files of the session it resumed.
  for (std::size_t session = 2; session <= 3; ++session) {
    ASSERT_EQ(replay((dir_ / "s.lcmlog").string(), args, &log), 0) << log;
    EXPECT_THAT(log, HasSubstr("(after cycle " + std::to_string((session - 1) * cycles) + ")")) << session;
  }
  auto files = checkpoint_files(state);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(slamd::read_checkpoint(files.back().string()).sequence, 3 * cycles);
  // --fresh: a new map, whose checkpoints are the newest from its first cycle on.
  ASSERT_EQ(replay((dir_ / "s.lcmlog").string(), {"--state-dir", state.string(), "--checkpoint-keep", "2", "--fresh"},
                   &log),
            0)
      << log;
  EXPECT_THAT(log, Not(HasSubstr("resuming")));
  ASSERT_EQ(replay((dir_ / "s.lcmlog").string(), args, &log), 0) << log;
  EXPECT_THAT(log, HasSubstr("(after cycle " + std::to_string(cycles) + ")"));
}

TEST_F(SlamdBinary, AMapOfAnotherModeIsNeitherLoadedNorRotatedOut) {
  const fs::path state = fresh_dir("other_mode");
  std::string log;
  ASSERT_EQ(replay((dir_ / "vita.lcmlog").string(), {"--state-dir", state.string()}, &log), 0) << log;
  const auto before = checkpoint_files(state);
  ASSERT_FALSE(before.empty());
  ASSERT_EQ(replay((dir_ / "tactile.lcmlog").string(), {"--state-dir", state.string(), "--mode", "tactile"}, &log), 1);
  EXPECT_THAT(log, HasSubstr("cannot resume from " + before.back().string() + ": "));
  EXPECT_THAT(log, HasSubstr("to keep that map, move it out of " + state.string() + " first; then start with --fresh"));
  EXPECT_EQ(checkpoint_files(state), before) << "nothing renamed, nothing rotated out";
}

TEST_F(SlamdBinary, LocalisesInASavedMapWithoutGrowingIt) {
  const fs::path state = fresh_dir("state_map");
  ASSERT_EQ(replay((dir_ / "map.lcmlog").string(), {"--state-dir", state.string(), "--checkpoint-keep", "1"}), 0);
  const SlamdOutput built = read_slamd_output((dir_ / "map.lcmlog").string());
  fs::path map_file;
  for (const auto& e : fs::directory_iterator(state)) map_file = e.path();
  ASSERT_FALSE(map_file.empty());

  const std::string out = (dir_ / "localise.lcmlog").string();
  std::string log;
  ASSERT_EQ(replay(out, {"--map", map_file.string(), "--localise"}, &log), 0) << log;
  EXPECT_THAT(log, HasSubstr("localising without growing it"));
  const SlamdOutput o = read_slamd_output(out);
  ASSERT_FALSE(o.events.empty());
  int relocalisations = 0;
  for (const auto& e : o.events) {
    EXPECT_NE(e.type, vita_event_t::NEW_EXPERIENCE) << "cycle " << e.cycle;
    relocalisations += e.type == vita_event_t::RELOCALISE;
  }
  EXPECT_GT(relocalisations, 0) << "the same route is recognised in the saved map";
  ASSERT_FALSE(o.maps.empty());
  EXPECT_EQ(o.maps.back().num_experiences, built.maps.back().num_experiences);
  EXPECT_EQ(o.maps.back().num_links, built.maps.back().num_links);

  // Growing a saved map into a state directory that holds another map's checkpoints would rotate
  // them out: refused, naming both, unless --fresh says to let them go.
  const fs::path other = dir_ / "state_other";
  fs::remove_all(other);
  ASSERT_EQ(replay((dir_ / "map.lcmlog").string(), {"--state-dir", other.string()}), 0);
  const auto held = checkpoint_files(other);
  ASSERT_FALSE(held.empty());
  EXPECT_EQ(replay(out, {"--map", map_file.string(), "--state-dir", other.string()}, &log), 1);
  EXPECT_THAT(log, HasSubstr("the state directory " + other.string() + " holds "));
  EXPECT_THAT(log, HasSubstr("growing --map " + map_file.string() + " would rotate out"));
  EXPECT_EQ(checkpoint_files(other), held) << "nothing written, nothing rotated out";
  EXPECT_EQ(replay(out, {"--map", map_file.string(), "--state-dir", other.string(), "--fresh"}, &log), 0) << log;
}

TEST_F(SlamdBinary, BadInvocationsFailWithAOneLineReason) {
  const std::string bad = (dir_ / "bad.yaml").string();
  std::ofstream(bad) << "slam:\n  match:\n    shift_maxx: 3\n";
  // A bad configuration exits 2, as in the drivers: the units do not restart on it.
  Subprocess p1({kSlamd, "--config", bad, "--print-config"});
  EXPECT_EQ(p1.wait(30), 2);
  EXPECT_THAT(p1.output(), HasSubstr("slamd: bad config: "));
  EXPECT_THAT(p1.output(), HasSubstr("unknown key 'slam.match.shift_maxx'"));
  Subprocess p2({kSlamd, "--mode", "sonar", "--print-config"});
  EXPECT_EQ(p2.wait(30), 2);
  EXPECT_THAT(p2.output(), HasSubstr("sonar"));
  Subprocess p3({kSlamd, "--localise"});
  EXPECT_NE(p3.wait(30), 0);
  EXPECT_THAT(p3.output(), HasSubstr("--map"));
  Subprocess p4({kSlamd, "--config", kConfig, "--print-config"});
  EXPECT_EQ(p4.wait(30), 0);
  EXPECT_THAT(p4.output(), HasSubstr("slam.match.threshold_vita: "));
  // --set: a key no parameter has, one without a value, and a value out of range.
  Subprocess p5({kSlamd, "--config", kConfig, "--set", "slam.match.tactile_vet=1", "--print-config"});
  EXPECT_EQ(p5.wait(30), 2);
  EXPECT_THAT(p5.output(), HasSubstr("--set: 'slam.match.tactile_vet' is not a parameter"));
  Subprocess p6({kSlamd, "--config", kConfig, "--set", "slam.match.tactile_veto", "--print-config"});
  EXPECT_EQ(p6.wait(30), 2);
  EXPECT_THAT(p6.output(), HasSubstr("expected KEY=VALUE"));
  Subprocess p7({kSlamd, "--config", kConfig, "--set", "slam.match.tactile_veto=-1", "--print-config"});
  EXPECT_EQ(p7.wait(30), 2);
  EXPECT_THAT(p7.output(), HasSubstr("slam.match.tactile_veto"));
}

// --output onto a file slamd reads (the replayed log by its own path, a hard link or a symbolic link
// to it; the config): refused before the output is opened, one line, exit 2, and the file untouched.
// It was truncated to 0 bytes, and the replay then failed ("the LCM log got shorter while being read").
TEST_F(SlamdBinary, AnOutputThatIsAFileItReadsIsRefusedAndLeftUntouched) {
  const std::string log = (dir_ / "input.lcmlog").string();
  fs::copy_file(sim_log_, log, fs::copy_options::overwrite_existing);
  const std::string before = slurp(log);
  const std::string hard = (dir_ / "hard.lcmlog").string();
  const std::string soft = (dir_ / "soft.lcmlog").string();
  fs::remove(hard);
  fs::remove(soft);
  fs::create_hard_link(log, hard);
  fs::create_symlink(log, soft);
  for (const std::string& out : {log, hard, soft, (dir_ / "." / "input.lcmlog").string()}) {
    Subprocess p({kSlamd, "--replay", log, "--output", out, "--config", kConfig});
    EXPECT_EQ(p.wait(60), 2) << p.output();
    EXPECT_EQ(p.output(), "slamd: --output " + out + " is the file given to --replay (" + log +
                              "): writing it would destroy it\n");
    EXPECT_EQ(fs::file_size(log), before.size()) << "-o " << out << " touched the input";
  }
  EXPECT_TRUE(slurp(log) == before);
  EXPECT_TRUE(fs::is_symlink(soft));

  const std::string config = (dir_ / "slam.yaml").string();
  fs::copy_file(kConfig, config, fs::copy_options::overwrite_existing);
  Subprocess p({kSlamd, "--replay", log, "--output", config, "--config", config});
  EXPECT_EQ(p.wait(60), 2) << p.output();
  EXPECT_THAT(p.output(), HasSubstr("is the file given to --config"));
  EXPECT_EQ(slurp(config), slurp(kConfig));
}

// --set overrides a parameter of the file, as --print-config shows and a run uses.
TEST_F(SlamdBinary, SetOverridesAParameterOfTheFile) {
  Subprocess p({kSlamd, "--config", kConfig, "--set", "slam.experience_map.drift_per_m=1000", "--set",
                "slam.match.tactile_veto=0", "--print-config"});
  ASSERT_EQ(p.wait(30), 0) << p.output();
  EXPECT_THAT(p.output(), HasSubstr("slam.experience_map.drift_per_m: 1000  (--set)"));
  EXPECT_THAT(p.output(), HasSubstr("slam.match.tactile_veto: 0  (--set)"));
}

// config/slam.yaml documents the defaults: slamd without --config must run with the same values,
// or a robot started from the unit file and a user replaying by hand would get different maps.
TEST_F(SlamdBinary, ShippedConfigEqualsTheCompiledDefaults) {
  auto slam_lines = [](const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("slam.", 0) != 0 && line.rfind("slamd.", 0) != 0) continue;
      const auto tag = line.find("  (default)");
      if (tag != std::string::npos) line.erase(tag);
      lines.push_back(line);
    }
    return lines;
  };
  Subprocess compiled({kSlamd, "--print-config"});
  ASSERT_EQ(compiled.wait(30), 0) << compiled.output();
  Subprocess shipped({kSlamd, "--config", kConfig, "--print-config"});
  ASSERT_EQ(shipped.wait(30), 0) << shipped.output();
  const auto a = slam_lines(compiled.output());
  EXPECT_GT(a.size(), 40u);
  EXPECT_EQ(a, slam_lines(shipped.output()));
}

// Runs inside a private network namespace (the test binary is started by scripts/netns-run).
TEST_F(SlamdBinary, KilledWithoutWarningItResumesFromItsNewestCheckpoint) {
  // SIGKILL (power loss, the OOM killer, a watchdog's SIGABRT) at any moment, also while a
  // checkpoint is being written: what is on disk must load, and the next start resumes from it.
  const fs::path state = fresh_dir("killed_state");
  Subprocess slamd({kSlamd, "--config", kConfig, "--state-dir", state.string()});
  ASSERT_TRUE(started(slamd)) << slamd.output();
  Subprocess player({"lcm-logplayer", "--speed", "4", sim_log_});
  ASSERT_TRUE(wait_until([&] { return fs::exists(state) && checkpoint_files(state).size() >= 3; }, 30)) << slamd.output();
  slamd.signal(SIGKILL);
  EXPECT_EQ(slamd.wait(10), 128 + SIGKILL);
  player.stop(5, SIGINT);
  const auto files = checkpoint_files(state);
  ASSERT_FALSE(files.empty());
  const slamd::Checkpoint newest = slamd::read_checkpoint(files.back().string());
  EXPECT_GT(newest.sequence, 0u);

  const std::string out = (dir_ / "after_kill.lcmlog").string();
  std::string log;
  ASSERT_EQ(replay(out, {"--state-dir", state.string()}, &log), 0) << log;
  EXPECT_THAT(log, HasSubstr("resuming from " + files.back().string() + " (after cycle " +
                             std::to_string(newest.sequence) + ")"));
  for (const auto& e : fs::directory_iterator(state)) {
    EXPECT_NE(e.path().extension(), ".tmp") << "an interrupted write is cleaned up: " << e.path();
  }
}

TEST_F(SlamdBinary, LiveRunFedByLcmLogplayerTakesTheSameDecisionsAsReplay) {
  const std::string replayed = (dir_ / "reference.lcmlog").string();
  ASSERT_EQ(replay(replayed), 0);
  const SlamdOutput reference = read_slamd_output(replayed);

  LcmBus bus;
  DecodeErrors errors;
  std::vector<vita_event_t> live;
  subscribe<vita_event_t>(bus, "VITA_EVENT", [&](const vita_event_t& m) { live.push_back(m); }, errors);
  slam_status_t status;
  int statuses = 0;
  subscribe<slam_status_t>(bus, "SLAM_STATUS", [&](const slam_status_t& m) {
    status = m;
    ++statuses;
  }, errors);

  // As shipped: a checkpoint after every cycle, written by slamd's writer thread.
  const fs::path state = fresh_dir("live_state");
  Subprocess slamd({kSlamd, "--config", kConfig, "--state-dir", state.string()});
  ASSERT_TRUE(started(slamd)) << slamd.output();
  Subprocess player({"lcm-logplayer", "--speed", "2", sim_log_});
  bool done = false;
  while (!done) {
    bus.handle_timeout(50);
    done = !player.running();
  }
  EXPECT_EQ(player.wait(1), 0) << player.output();
  // Let the last messages drain.
  for (int i = 0; i < 40; ++i) bus.handle_timeout(50);
  EXPECT_EQ(slamd.stop(20, SIGTERM), 0) << slamd.output();
  EXPECT_THAT(slamd.output(), HasSubstr("stopped after"));
  // Checkpoints were written while it ran, none failed, and the newest holds the last cycle.
  ASSERT_GT(statuses, 0);
  EXPECT_GT(status.checkpoints_written, 0);
  EXPECT_EQ(status.checkpoint_errors, 0);
  const std::string out = slamd.output();
  const std::size_t at = out.find("stopped after ");
  ASSERT_NE(at, std::string::npos);
  const uint64_t cycles = std::stoull(out.substr(at + 14));
  EXPECT_GE(cycles, live.size());
  const auto files = checkpoint_files(state);
  ASSERT_FALSE(files.empty());
  EXPECT_EQ(slamd::read_checkpoint(files.back().string()).sequence, cycles) << files.back();

  // The last cycle of a log may still be waiting for a camera frame after its end when the log
  // stops; --replay flushes it, a live daemon keeps it pending. Everything before must agree.
  ASSERT_GE(live.size() + 1, reference.events.size()) << slamd.output();
  ASSERT_LE(live.size(), reference.events.size());
  for (std::size_t i = 0; i < live.size(); ++i) {
    EXPECT_EQ(live[i].cycle, reference.events[i].cycle) << i;
    EXPECT_EQ(live[i].type, reference.events[i].type) << i;
    EXPECT_EQ(live[i].from_id, reference.events[i].from_id) << i;
    EXPECT_EQ(live[i].to_id, reference.events[i].to_id) << i;
    EXPECT_EQ(live[i].template_id, reference.events[i].template_id) << i;
  }
  EXPECT_EQ(errors.total(), 0);
}

// A burst of input that arrives faster than slamd's loop takes it (a sender catching up after a
// pause, a busy cycle, a replay at speed) is taken whole. LCM keeps 30 unhandled messages per
// subscription and drops the rest without a trace: a live slamd lost odometry that a replay of the
// same messages had, and its map drifted apart from the replay's (the chaos test's rare divergence,
// docs/reliability.md). Here slamd is stopped (SIGSTOP) while 9 s of odometry are published, so the
// whole burst is waiting on its socket when it continues.
class SlamdBurst : public SlamdBinary {
 protected:
  // `suffix`: the inputs renamed (slam.yaml's slamd.channel_*, here by --set) to their names plus it.
  void a_burst_is_taken_whole(const std::string& suffix);
};

void SlamdBurst::a_burst_is_taken_whole(const std::string& suffix) {
  LcmBus bus;
  DecodeErrors errors;
  std::set<int64_t> poses;  // VITA_POSE: one per odometry sample taken, once a cycle is done
  int events = 0;
  auto last_message = std::chrono::steady_clock::now();
  subscribe<vita_pose_t>(bus, "VITA_POSE", [&](const vita_pose_t& m) {
    poses.insert(m.utime);
    last_message = std::chrono::steady_clock::now();
  }, errors);
  bus.set_queue_capacity("VITA_POSE", 0);  // the test's own subscription takes the whole burst too
  subscribe<vita_event_t>(bus, "VITA_EVENT", [&](const vita_event_t&) {
    ++events;
    last_message = std::chrono::steady_clock::now();
  }, errors);

  const fs::path state = fresh_dir("burst_state");
  std::vector<std::string> argv{kSlamd, "--config", kConfig, "--state-dir", state.string()};
  if (!suffix.empty()) {
    for (const std::string input : {"odometry", "camera", "cycle"}) {
      const std::string name = input == "odometry" ? "ODOMETRY" : input == "camera" ? "CAMERA" : "WHISK_CYCLE";
      argv.insert(argv.end(), {"--set", "slamd.channel_" + input + "=" + name + suffix});
    }
  }
  Subprocess slamd(argv);
  ASSERT_TRUE(started(slamd)) << slamd.output();

  // The first 5 s of the run at 4x real time: cycles are done, so each later sample gives a pose.
  LogReader reader(sim_log_);
  LogReader::EventView ev;
  const auto start = std::chrono::steady_clock::now();
  int64_t t0 = -1;
  std::vector<int64_t> burst;  // sample times of the odometry published in the burst
  while (reader.next(ev)) {
    const std::string channel(ev.channel);
    if (channel != "ODOMETRY" && channel != "CAMERA" && channel != "WHISK_CYCLE") continue;
    if (t0 < 0) t0 = ev.utime;
    if (ev.utime - t0 < 5'000'000) {
      std::this_thread::sleep_until(start + std::chrono::microseconds((ev.utime - t0) / 4));
      bus.publish_raw(channel + suffix, ev.data);
      while (bus.handle_timeout(0) > 0) {
      }
      continue;
    }
    if (burst.empty()) {
      ASSERT_TRUE(wait_until([&] {
        while (bus.handle_timeout(0) > 0) {
        }
        return events > 0 && std::chrono::steady_clock::now() - last_message > std::chrono::milliseconds(500);
      }, 20)) << slamd.output();
      slamd.signal(SIGSTOP);
    }
    if (channel != "ODOMETRY") continue;
    odometry_t odometry;
    ASSERT_TRUE(decode_message(ev.data, odometry));
    bus.publish_raw(channel + suffix, ev.data);
    burst.push_back(odometry.utime);
  }
  ASSERT_GT(burst.size(), 300u);
  slamd.signal(SIGCONT);
  const auto missing = [&] {
    std::size_t n = 0;
    for (int64_t t : burst) n += poses.count(t) == 0 ? 1 : 0;
    return n;
  };
  wait_until([&] {
    while (bus.handle_timeout(0) > 0) {
    }
    return missing() == 0;
  }, 20);
  EXPECT_EQ(missing(), 0u) << "of the " << burst.size() << " odometry samples of the burst";
  EXPECT_EQ(slamd.stop(20, SIGTERM), 0) << slamd.output();
  EXPECT_EQ(errors.total(), 0);
}

// SIGTERM right after a burst: what LCM already holds goes into the final state. slamd once left
// its loop at the signal and flushed, and the cycles still in LCM's queues were never mapped.
TEST_F(SlamdBurst, WhatArrivedBeforeSigtermGoesIntoTheFinalState) {
  LcmBus bus;
  const fs::path state = fresh_dir("sigterm_state");
  Subprocess slamd({kSlamd, "--config", kConfig, "--state-dir", state.string()});
  ASSERT_TRUE(started(slamd)) << slamd.output();
  LogReader reader(sim_log_);
  LogReader::EventView ev;
  int64_t t0 = -1;
  uint64_t cycles = 0;
  bool stopped = false;
  const auto start = std::chrono::steady_clock::now();
  while (reader.next(ev)) {
    const std::string channel(ev.channel);
    if (channel != "ODOMETRY" && channel != "CAMERA" && channel != "WHISK_CYCLE") continue;
    if (t0 < 0) t0 = ev.utime;
    if (ev.utime - t0 >= 8'000'000) break;
    if (ev.utime - t0 >= 4'000'000 && !stopped) {  // 4 s taken as they come; then a burst of 4 s
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      slamd.signal(SIGSTOP);
      stopped = true;
    }
    if (stopped && channel == "CAMERA") continue;  // the burst: whisk cycles and odometry
    if (!stopped) std::this_thread::sleep_until(start + std::chrono::microseconds((ev.utime - t0) / 4));  // 4x
    bus.publish_raw(channel, ev.data);
    if (channel == "WHISK_CYCLE") ++cycles;
  }
  ASSERT_TRUE(stopped);
  slamd.signal(SIGCONT);
  slamd.signal(SIGTERM);
  ASSERT_EQ(slamd.wait(30), 0) << slamd.output();
  const std::string out = slamd.output();
  const std::size_t at = out.find("stopped after ");
  ASSERT_NE(at, std::string::npos) << out;
  EXPECT_EQ(std::stoull(out.substr(at + 14)), cycles) << "of the whisk cycles published" << out;
  const auto files = checkpoint_files(state);
  ASSERT_FALSE(files.empty());
  EXPECT_EQ(slamd::read_checkpoint(files.back().string()).sequence, cycles) << files.back();
}

TEST_F(SlamdBurst, ABurstOfOdometryThatArrivedWhileItWasStoppedIsTakenWhole) {
  a_burst_is_taken_whole("");
}

// The input queues follow the configured channel names: renamed inputs fell back to LCM's 30
// messages, and the burst was lost.
TEST_F(SlamdBurst, OnRenamedInputChannelsTooIsTakenWhole) {
  a_burst_is_taken_whole("_RENAMED");
}

}  // namespace
}  // namespace whiskeye
