// The vita-sim executable: reproducible logs, channels and rates in the log, time order, errors; the
// candump log of the whisker boards' CAN frames decoded back against the LCM log of the same run.
#include "sim_test_util.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/sim/can_log.h"
#include "whiskeye/sim/simulator.h"
#include "whiskeye/whiskerd/config.h"

#include <whiskeye/contact_truth_t.hpp>
#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/sim_fault_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <tuple>

namespace whiskeye::sim {
namespace {

namespace fs = std::filesystem;

std::string temp_path(const std::string& name) {
  return (fs::temp_directory_path() / ("vita_sim_test_" + std::to_string(getpid()) + "_" + name)).string();
}

int vita_sim(const std::string& args) {
  const std::string cmd = std::string(VITA_SIM_EXE) + " --robot " + test::source_path("config/robot.yaml") + " " + args +
                          " -q 2>/dev/null";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string arena() { return "--world " + test::source_path("config/worlds/aliased_arena.yaml"); }

// Runs vita-sim with its stderr in `err`; returns the exit code.
int vita_sim_stderr(const std::string& args, std::string& err) {
  const std::string path = temp_path("stderr.txt");
  const std::string cmd = std::string(VITA_SIM_EXE) + " --robot " + test::source_path("config/robot.yaml") + " " + args +
                          " -q 2>" + path;
  const int status = std::system(cmd.c_str());
  std::ifstream in(path);
  err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  fs::remove(path);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

template <typename T>
int64_t utime_of(const LogEvent& e) {
  T msg;
  EXPECT_TRUE(decode_message(std::span<const uint8_t>(e.data), msg)) << e.channel;
  return msg.utime;
}

TEST(VitaSim, SameSeedGivesAByteIdenticalLogAndAnotherSeedDoesNot) {
  const std::string a = temp_path("a.lcmlog");
  const std::string b = temp_path("b.lcmlog");
  const std::string c = temp_path("c.lcmlog");
  ASSERT_EQ(vita_sim(arena() + " --duration 2 --seed 3 -o " + a), 0);
  ASSERT_EQ(vita_sim(arena() + " --duration 2 --seed 3 -o " + b), 0);
  ASSERT_EQ(vita_sim(arena() + " --duration 2 --seed 4 -o " + c), 0);
  const std::string sa = slurp(a);
  EXPECT_GT(sa.size(), 1000000u);
  EXPECT_TRUE(sa == slurp(b));
  EXPECT_FALSE(sa == slurp(c));
  fs::remove(a);
  fs::remove(b);
  fs::remove(c);
}

TEST(VitaSim, LogHasTheDriversChannelsAtTheirRatesStampedWithSampleTimesInOrder) {
  const std::string path = temp_path("rates.lcmlog");
  ASSERT_EQ(vita_sim(arena() + " --duration 3 --start-utime 5000000 -o " + path), 0);
  LogReader log(path);
  LogEvent e;
  std::map<std::string, int> count;
  int64_t last = 0;
  while (log.next(e)) {
    ++count[e.channel];
    ASSERT_GE(e.utime, last) << "events out of time order at " << e.channel;
    last = e.utime;
    int64_t msg_utime = -1;
    if (e.channel == "WHISKER_SAMPLE") msg_utime = utime_of<whisker_sample_t>(e);
    if (e.channel == "RCP_STATE") msg_utime = utime_of<rcp_state_t>(e);
    if (e.channel == "WHISK_CYCLE") msg_utime = utime_of<whisk_cycle_t>(e);
    if (e.channel == "SIM_CONTACT_TRUTH") msg_utime = utime_of<contact_truth_t>(e);
    if (e.channel == "ODOMETRY") msg_utime = utime_of<odometry_t>(e);
    if (e.channel == "GROUND_TRUTH") msg_utime = utime_of<pose2d_t>(e);
    if (e.channel == "SIM_FAULT") msg_utime = utime_of<sim_fault_t>(e);
    if (e.channel == "CAMERA") {
      image_t img;
      ASSERT_TRUE(decode_message(std::span<const uint8_t>(e.data), img));
      EXPECT_EQ(img.width, 640);
      EXPECT_EQ(img.height, 480);
      EXPECT_EQ(img.pixelformat, image_t::PIXEL_FORMAT_YUYV);
      EXPECT_EQ(img.size, 640 * 480 * 2);
      EXPECT_EQ(img.row_stride, 640 * 2);
      msg_utime = img.utime;
    }
    ASSERT_NE(msg_utime, -1) << "unexpected channel " << e.channel;
    EXPECT_EQ(e.utime, msg_utime) << e.channel;
  }
  EXPECT_EQ(count["WHISKER_SAMPLE"], 1500);
  EXPECT_EQ(count["RCP_STATE"], 1500);
  EXPECT_EQ(count["ODOMETRY"], 150);
  EXPECT_EQ(count["GROUND_TRUTH"], 150);
  EXPECT_EQ(count["CAMERA"], 15);
  EXPECT_GE(count["WHISK_CYCLE"], 2);
  EXPECT_EQ(count["SIM_CONTACT_TRUTH"], count["WHISK_CYCLE"]);
  fs::remove(path);
}

TEST(VitaSim, PlotsTheWorldAsAPng) {
  const std::string png = temp_path("world.png");
  ASSERT_EQ(vita_sim(arena() + " --plot-world " + png), 0);
  const std::string bytes = slurp(png);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
  fs::remove(png);
}

TEST(VitaSim, FramesDirPngsHoldExactlyTheLoggedFramesAndThePlotsDecode) {
  const std::string log = temp_path("frames.lcmlog");
  const std::string dir = temp_path("frames");
  const std::string world_png = temp_path("plot_world.png");
  const std::string views_png = temp_path("plot_views.png");
  ASSERT_EQ(vita_sim(arena() + " --duration 1 --seed 3 --frames-dir " + dir + " --frames-every 2 -o " + log), 0);
  LogReader reader(log);
  LogEvent e;
  int compared = 0;
  while (reader.next(e)) {
    if (e.channel != "CAMERA") continue;
    image_t img;
    ASSERT_TRUE(decode_message(std::span<const uint8_t>(e.data), img));
    char name[64];
    std::snprintf(name, sizeof name, "/frame_%06lld.png", static_cast<long long>(img.seq));
    const cv::Mat png = cv::imread(dir + name, cv::IMREAD_UNCHANGED);
    if (img.seq % 2 != 0) {
      EXPECT_TRUE(png.empty()) << name << ": only every second frame";
      continue;
    }
    ASSERT_EQ(png.type(), CV_8UC1) << name;
    ASSERT_EQ(png.cols, img.width);
    ASSERT_EQ(png.rows, img.height);
    for (int y = 0; y < img.height; ++y) {
      for (int x = 0; x < img.width; ++x) {
        ASSERT_EQ(png.at<uint8_t>(y, x), img.data[static_cast<std::size_t>(y) * img.row_stride + 2 * x]) << name;
      }
    }
    ++compared;
  }
  EXPECT_EQ(compared, 3) << "frames 0, 2, 4 of 5";
  ASSERT_EQ(vita_sim(arena() + " --plot-world " + world_png + " --plot-views " + views_png), 0);
  const cv::Mat world = cv::imread(world_png, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(world.type(), CV_8UC3);
  EXPECT_GT(world.cols, 660) << "the figure's square map and its legend";
  // Something other than the white background, in colour: the landmarks.
  cv::Mat channels[3];
  cv::split(world, channels);
  EXPECT_GT(cv::norm(channels[0], channels[2], cv::NORM_L1), 0.0);
  const cv::Mat views = cv::imread(views_png, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(views.type(), CV_8UC1);
  EXPECT_EQ(views.cols, 640) << "two half-size views a row";
  fs::remove(log);
  fs::remove_all(dir);
  fs::remove(world_png);
  fs::remove(views_png);
}

TEST(VitaSim, BadInputExitsNonZero) {
  const std::string bad = temp_path("bad.yaml");
  std::ofstream(bad) << "world:\n  walls: [{from: [0, 0], to: [1, 0], pattern: missing}]\n";
  EXPECT_NE(vita_sim("--world " + bad + " -o " + temp_path("x.lcmlog")), 0);
  EXPECT_NE(vita_sim(arena()), 0);  // no output
  fs::remove(bad);
}

// No output onto a file vita-sim reads (by its path, a hard link or a symbolic link): one line, exit 2,
// before anything is opened (the LCM log and the candump were truncated when opened), the file intact.
TEST(VitaSim, AnOutputThatIsAFileItReadsIsRefusedBeforeAnythingIsOpened) {
  const std::string world = temp_path("own_world.yaml"), hard = temp_path("own_hard.yaml"), soft = temp_path("own_soft.yaml");
  const std::string whiskerd = temp_path("own_whiskerd.yaml");
  fs::copy_file(test::source_path("config/worlds/aliased_arena.yaml"), world, fs::copy_options::overwrite_existing);
  fs::copy_file(test::source_path("config/whiskerd.yaml"), whiskerd, fs::copy_options::overwrite_existing);
  fs::remove(hard);
  fs::remove(soft);
  fs::create_hard_link(world, hard);
  fs::create_symlink(world, soft);
  const std::string world_text = slurp(world), whiskerd_text = slurp(whiskerd);
  const std::string refused = " is the file given to --world (" + world + "): writing it would destroy it\n";
  const std::pair<std::string, std::string> cases[] = {
      {"-o " + world, "vita-sim: --output " + world + refused},
      {"-o " + hard, "vita-sim: --output " + hard + refused},
      {"--candump " + soft, "vita-sim: --candump " + soft + refused},
      {"--plot-world " + world, "vita-sim: --plot-world " + world + refused},
      {"-o " + temp_path("own.lcmlog") + " --candump " + whiskerd + " --whiskerd-config " + whiskerd,
       "vita-sim: --candump " + whiskerd + " is the file given to --whiskerd-config (" + whiskerd +
           "): writing it would destroy it\n"},
  };
  for (const auto& [args, line] : cases) {
    std::string err;
    EXPECT_EQ(vita_sim_stderr("--world " + world + " --duration 1 " + args, err), 2) << args;
    EXPECT_EQ(err, line) << args;
  }
  std::string err;
  EXPECT_EQ(vita_sim_stderr("--bringup rest --candump " + temp_path("own.log") + " --whiskerd-config " + whiskerd +
                                " --write-true-calibration " + whiskerd,
                            err),
            2);
  EXPECT_EQ(err, "vita-sim: --write-true-calibration " + whiskerd + " is the file given to --whiskerd-config (" +
                     whiskerd + "): writing it would destroy it\n");
  EXPECT_TRUE(slurp(world) == world_text);
  EXPECT_TRUE(slurp(whiskerd) == whiskerd_text);
  EXPECT_TRUE(fs::is_symlink(soft));
  EXPECT_FALSE(fs::exists(temp_path("own.lcmlog")));
  EXPECT_FALSE(fs::exists(temp_path("own.log")));
  for (const std::string& f : {world, hard, soft, whiskerd}) fs::remove(f);
}

TEST(VitaSim, LapsAndDurationBeyondTheWorldFilesBoundsExitWith2NamingTheOption) {
  // An output vita-sim cannot create: were a bound missing, the run would fail at once (exit 1)
  // instead of writing for days.
  const std::string out = "/nonexistent/dir/bounds.lcmlog";
  for (const char* args : {"--laps 1000000000", "--laps 10001", "--laps 0", "--laps -3"}) {
    std::string err;
    EXPECT_EQ(vita_sim_stderr(arena() + " " + args + " -o " + out, err), 2) << args;
    EXPECT_EQ(err.rfind("vita-sim: --laps ", 0), 0u) << args << ": " << err;
    EXPECT_NE(err.find("10000"), std::string::npos) << "names the bound: " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  // The arena's lap is 62.8 s: 10000 laps are 628,319 s.
  for (const char* args : {"--duration 628400", "--duration 1e300", "--duration inf", "--duration nan", "--duration 0",
                           "--duration -1"}) {
    std::string err;
    EXPECT_EQ(vita_sim_stderr(arena() + " " + args + " -o " + out, err), 2) << args;
    EXPECT_EQ(err.rfind("vita-sim: --duration ", 0), 0u) << args << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  // The bound itself is allowed (the duration overrides the laps, so this runs one second).
  const std::string ok = temp_path("bounds.lcmlog");
  std::string err;
  EXPECT_EQ(vita_sim_stderr(arena() + " --laps 10000 --duration 1 -o " + ok, err), 0) << err;
  fs::remove(ok);
}

// The first GROUND_TRUTH sample of a log, and every SIM_FAULT with the ground truth at its time.
struct TruthAndFaults {
  int64_t first_utime = -1;
  pose2d_t first;
  std::vector<std::pair<sim_fault_t, pose2d_t>> faults;
};

TruthAndFaults read_truth_and_faults(const std::string& path) {
  TruthAndFaults r;
  LogReader log(path);
  LogEvent e;
  std::vector<sim_fault_t> pending;
  while (log.next(e)) {
    if (e.channel == "SIM_FAULT") {
      sim_fault_t m;
      EXPECT_TRUE(decode_message(std::span<const uint8_t>(e.data), m));
      pending.push_back(m);
    } else if (e.channel == "GROUND_TRUTH") {
      pose2d_t m;
      EXPECT_TRUE(decode_message(std::span<const uint8_t>(e.data), m));
      if (r.first_utime < 0) {
        r.first_utime = m.utime;
        r.first = m;
      }
      for (const sim_fault_t& f : pending) {
        if (f.utime == m.utime) r.faults.emplace_back(f, m);
      }
      pending.clear();
    }
  }
  return r;
}

TEST(VitaSim, ASecondSessionStartsAtTheGivenPhaseOfThePathAndOnTheGivenClock) {
  const std::string out = temp_path("session2.lcmlog");
  std::string err;
  ASSERT_EQ(vita_sim_stderr(arena() + " --duration 1 --start-phase 1.2 --start-utime 1700000900000000 -o " + out, err), 0)
      << err;
  const TruthAndFaults r = read_truth_and_faults(out);
  EXPECT_EQ(r.first_utime, 1'700'000'900'000'000);
  EXPECT_NEAR(r.first.x, std::cos(1.2), 1e-9) << "the arena's path: radius 1 m around the origin";
  EXPECT_NEAR(r.first.y, std::sin(1.2), 1e-9);
  EXPECT_NEAR(r.first.theta, 1.2, 1e-9) << "facing outwards";
  fs::remove(out);
  for (const char* args : {"--start-phase 6.3", "--start-phase -7", "--start-phase nan", "--start-phase inf",
                           "--start-utime -1", "--start-utime 5000000000000000000"}) {
    EXPECT_EQ(vita_sim_stderr(arena() + " " + args + " --duration 1 -o /nonexistent/dir/x.lcmlog", err), 2) << args;
    const std::string option = std::string(args).substr(0, std::string(args).find(' '));
    EXPECT_EQ(err.rfind("vita-sim: " + option + " ", 0), 0u) << args << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
}

TEST(VitaSim, AKidnapIsLoggedOnSimFaultWithThePoseTheRobotWasPutDownAtAndSummarised) {
  const std::string world = temp_path("kidnap_world.yaml");
  std::ofstream(world) << std::ifstream(test::source_path("config/worlds/aliased_arena.yaml")).rdbuf()
                       << "  faults:\n    kidnap: [{at: 0.5, to_angle: 3.0}, {at: 5.0, to_angle: 1.0}]\n";
  const std::string out = temp_path("kidnap.lcmlog");
  std::string err;
  ASSERT_EQ(vita_sim_stderr("--world " + world + " --duration 1 -o " + out, err), 0) << err;
  EXPECT_NE(err.find("fault kidnap to polar angle 171.9 deg: at 0.500 s, put down at x -0.990 m, y 0.141 m, heading "
                     "171.9 deg"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("fault kidnap to polar angle 57.3 deg: not reached (the run ended first)"), std::string::npos) << err;
  const TruthAndFaults r = read_truth_and_faults(out);
  ASSERT_EQ(r.faults.size(), 1u);
  const auto& [f, truth] = r.faults[0];
  EXPECT_EQ(f.kind, sim_fault_t::KIND_KIDNAP);
  EXPECT_TRUE(f.active);
  EXPECT_EQ(f.utime, SimParams{}.start_utime + 500'000);
  EXPECT_EQ(f.x, truth.x) << "the ground truth of the same instant";
  EXPECT_EQ(f.y, truth.y);
  EXPECT_EQ(f.theta, truth.theta);
  EXPECT_NEAR(f.x, std::cos(3.0), 1e-12);
  fs::remove(world);
  fs::remove(out);
}

// The arena with every kind of fault (a 3 s run).
std::string faulty_world() {
  const std::string path = temp_path("faulty_world.yaml");
  std::ofstream(path) << std::ifstream(test::source_path("config/worlds/aliased_arena.yaml")).rdbuf()
                      << "  faults:\n"
                         "    dead_whiskers: [3, 17]\n"
                         "    board_offline: [{board: 2, start: 0.5, duration: 1.0}]\n"
                         "    camera_blackout: [{start: 1.0, duration: 0.5}]\n"
                         "    camera_freeze: [{start: 2.0, duration: 0.5}]\n"
                         "    odometry_slip: [{start: 1.2, duration: 10.0, scale: 1.2}]\n";
  return path;
}

TEST(VitaSim, FromAnotherFolderFindsTheSourceTreesConfigsWithoutBeingGivenThem) {
  // No --robot and no --whiskerd-config, in a folder with no config/: the defaults come from the
  // program's location (a build tree: the source tree's config/), not the working directory.
  const fs::path dir = temp_path("elsewhere");
  fs::create_directories(dir);
  const std::string cmd = "cd " + dir.string() + " && " + VITA_SIM_EXE + " " + arena() +
                          " --duration 1 --seed 2 -o a.lcmlog --candump a.candump -q 2>err.txt";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp((dir / "err.txt").string());
  // The same bytes as with the source tree's configs named.
  const std::string b = temp_path("named.lcmlog");
  const std::string b_candump = temp_path("named.candump");
  ASSERT_EQ(vita_sim(arena() + " --duration 1 --seed 2 -o " + b + " --candump " + b_candump + " --whiskerd-config " +
                     test::source_path("config/whiskerd.yaml")),
            0);
  EXPECT_TRUE(slurp((dir / "a.lcmlog").string()) == slurp(b));
  EXPECT_TRUE(slurp((dir / "a.candump").string()) == slurp(b_candump));
  fs::remove_all(dir);
  fs::remove(b);
  fs::remove(b_candump);
}

TEST(VitaSim, AFaultyWorldsLogRecordsEachFaultOnSimFaultAndIsByteIdenticalForTheSameSeed) {
  const std::string world = faulty_world();
  const std::string a = temp_path("fa.lcmlog");
  const std::string b = temp_path("fb.lcmlog");
  const std::string candump = temp_path("fa.candump");
  const std::string cfg = " --whiskerd-config " + test::source_path("config/whiskerd.yaml");
  std::string err;
  ASSERT_EQ(vita_sim_stderr("--world " + world + " --duration 3 --seed 2 -o " + a + " --candump " + candump + cfg, err), 0)
      << err;
  ASSERT_EQ(vita_sim("--world " + world + " --duration 3 --seed 2 -o " + b), 0);
  EXPECT_TRUE(slurp(a) == slurp(b));
  // One summary line per fault.
  for (const char* line : {"fault dead_whiskers whisker 3: the whole run, 1500 samples flagged STATUS_FAULT",
                           "fault dead_whiskers whisker 17: the whole run",
                           "fault board_offline board 2: 0.500 s to 1.500 s, 500 board samples stale",
                           "fault camera_blackout: 1.000 s to 1.500 s, 3 camera frames withheld",
                           "fault camera_freeze: 2.000 s to 2.500 s, 3 camera frames repeated",
                           "fault odometry_slip x1.2: 1.200 s to the end of the run, 90 odometry samples scaled"}) {
    EXPECT_NE(err.find(line), std::string::npos) << line << "\n" << err;
  }
  const int64_t t0 = SimParams{}.start_utime;
  std::vector<sim_fault_t> faults;
  int64_t last = 0;
  int cameras = 0;
  LogReader log(a);
  LogEvent e;
  while (log.next(e)) {
    ASSERT_GE(e.utime, last);
    last = e.utime;
    if (e.channel == "SIM_FAULT") {
      sim_fault_t m;
      ASSERT_TRUE(decode_message(std::span<const uint8_t>(e.data), m));
      EXPECT_EQ(m.utime, e.utime);
      faults.push_back(m);
    } else if (e.channel == "CAMERA") {
      ++cameras;
      EXPECT_FALSE(e.utime >= t0 + 1'000'000 && e.utime < t0 + 1'500'000) << "a frame in the blackout";
    } else if (e.channel == "WHISKER_SAMPLE") {
      whisker_sample_t m;
      ASSERT_TRUE(decode_message(std::span<const uint8_t>(e.data), m));
      const bool offline = m.utime >= t0 + 500'000 && m.utime < t0 + 1'500'000;
      ASSERT_EQ(m.status[3] & whisker_sample_t::STATUS_FAULT, whisker_sample_t::STATUS_FAULT);
      ASSERT_EQ(m.deflection_x[3], 0.0f);
      for (int w = 8; w < 12; ++w) ASSERT_EQ((m.status[w] & whisker_sample_t::STATUS_STALE) != 0, offline) << m.utime;
    }
  }
  EXPECT_EQ(cameras, 12);
  const std::vector<std::tuple<int64_t, int, bool, int>> expected = {
      {0, sim_fault_t::KIND_DEAD_WHISKER, true, 3},          {0, sim_fault_t::KIND_DEAD_WHISKER, true, 17},
      {500'000, sim_fault_t::KIND_BOARD_OFFLINE, true, 2},    {1'000'000, sim_fault_t::KIND_CAMERA_BLACKOUT, true, -1},
      {1'200'000, sim_fault_t::KIND_ODOMETRY_SLIP, true, -1}, {1'500'000, sim_fault_t::KIND_BOARD_OFFLINE, false, 2},
      {1'500'000, sim_fault_t::KIND_CAMERA_BLACKOUT, false, -1}, {2'000'000, sim_fault_t::KIND_CAMERA_FREEZE, true, -1},
      {2'500'000, sim_fault_t::KIND_CAMERA_FREEZE, false, -1},
  };
  ASSERT_EQ(faults.size(), expected.size());
  for (std::size_t i = 0; i < faults.size(); ++i) {
    EXPECT_EQ(faults[i].utime - t0, std::get<0>(expected[i])) << i;
    EXPECT_EQ(faults[i].kind, std::get<1>(expected[i])) << i;
    EXPECT_EQ(faults[i].active, std::get<2>(expected[i])) << i;
    EXPECT_EQ(faults[i].index, std::get<3>(expected[i])) << i;
    EXPECT_EQ(faults[i].value, faults[i].kind == sim_fault_t::KIND_ODOMETRY_SLIP ? 1.2 : 0.0) << i;
  }
  // The offline board's CAN traffic stops for the interval: no sample frames, no heartbeats.
  std::ifstream in(candump);
  std::string line, iface;
  CanFrame f;
  int board2 = 0;
  while (std::getline(in, line)) {
    ASSERT_TRUE(parse_candump_line(line, f, iface)) << line;
    if (f.id != 0x183 && f.id != 0x703) continue;
    ++board2;
    EXPECT_FALSE(f.utime >= t0 + 500'000 && f.utime < t0 + 1'500'000) << line;
  }
  EXPECT_EQ(board2, 1000 + 20) << "2 s of FD samples at 500 Hz and of heartbeats at 10 Hz";
  for (const auto& p : {world, a, b, candump}) fs::remove(p);
}

// The arena started where the robot passes box_north within 2 s: contacts, large deflections.
std::string contact_world() {
  const std::string path = temp_path("contact_world.yaml");
  std::ifstream in(test::source_path("config/worlds/aliased_arena.yaml"));
  std::ofstream out(path);
  std::string line;
  int replaced = 0;
  while (std::getline(in, line)) {
    if (line.find("start_angle_deg:") != std::string::npos) {
      line = line.substr(0, line.find("start_angle_deg:")) + "start_angle_deg: 84";
      ++replaced;
    }
    out << line << "\n";
  }
  EXPECT_EQ(replaced, 1);
  return path;
}

// A whiskerd config with non-trivial calibrations (offset, gain, rotation, theta offset and gain).
std::string whiskerd_config() {
  const std::string path = temp_path("whiskerd.yaml");
  std::ofstream(path) << "can:\n  interface: vcan0\n"
                         "calibration:\n  whiskers:\n"
                         "    - {index: 23, offset_x: 50, gain_x: 0.0009}\n"
                         "    - {index: 22, rotation: 1.5707963267948966}\n"
                         "    - {index: 3, offset_y: -40, gain_y: -0.0004, rotation: -0.3}\n"
                         "    - {index: 9, theta_offset: 30, theta_gain: 0.0013}\n";
  return path;
}

struct CandumpCheck {
  int64_t frames = 0, heartbeats = 0, board_samples = 0, compared = 0, saturated = 0, contact_samples = 0;
  std::array<std::vector<int64_t>, wp::kNumBoards> sample_times;
};

// Parses the candump log line by line, decodes and assembles it as whiskerd does, calibrates it with
// whiskerd's calibration and compares every board sample with the WHISKER_SAMPLE of its utime.
CandumpCheck check_candump(const std::string& candump, const std::string& lcmlog, const std::string& config,
                           wp::BusMode mode) {
  whiskerd::Params params;
  whiskerd::load(ParamNode::from_file(config), params);
  std::map<int64_t, whisker_sample_t> truth;
  {
    LogReader log(lcmlog);
    LogEvent e;
    while (log.next(e)) {
      if (e.channel != "WHISKER_SAMPLE") continue;
      whisker_sample_t m;
      EXPECT_TRUE(decode_message(std::span<const uint8_t>(e.data), m));
      truth[m.utime] = m;
    }
  }
  CandumpCheck r;
  wp::SampleAssembler assembler(mode);
  std::ifstream in(candump);
  std::string line;
  std::string iface;
  CanFrame f;
  while (std::getline(in, line)) {
    if (!parse_candump_line(line, f, iface)) {
      ADD_FAILURE() << "unparsable line: " << line;
      continue;
    }
    ++r.frames;
    EXPECT_EQ(iface, "vcan0");
    const wp::Decoded d = wp::decode_frame(f.id, f.fd, f.data, mode, params.ids);
    int board = -1;
    if (d.kind == wp::FrameKind::kHeartbeat) {
      ++r.heartbeats;
      continue;
    }
    if (d.kind == wp::FrameKind::kSample && assembler.add(d.sample)) board = d.sample.board;
    if (d.kind == wp::FrameKind::kFragment && assembler.add(d.fragment)) board = d.fragment.board;
    if (d.kind == wp::FrameKind::kRejected) ADD_FAILURE() << wp::reject_text(d) << ": " << line;
    if (board < 0) continue;
    ++r.board_samples;
    r.sample_times[board].push_back(f.utime);
    const auto it = truth.find(f.utime);
    if (it == truth.end()) {
      ADD_FAILURE() << "no WHISKER_SAMPLE at " << f.utime;
      continue;
    }
    bool contact = false;
    for (int k = 0; k < wp::kWhiskersPerBoard; ++k) {
      const int w = board * wp::kWhiskersPerBoard + k;
      const wp::WhiskerCalibration& c = params.calibration[w];
      const wp::WhiskerRaw& raw = assembler.latest(board).whiskers[k];
      const wp::CalibratedWhisker back = wp::calibrate(raw, c);
      const auto& m = it->second;
      EXPECT_NEAR(back.theta, m.theta[w], 0.5 * std::abs(c.theta_gain) + 1e-6) << "whisker " << w << " at " << f.utime;
      contact = contact || std::hypot(m.deflection_x[w], m.deflection_y[w]) > 0.05;
      if (std::abs(raw.x) == wp::kHallLimit || std::abs(raw.y) == wp::kHallLimit) {
        ++r.saturated;
        continue;  // clipped as the ADC would be: the true value lies beyond full scale
      }
      // One quantisation step: half a count per sensor axis, through the gains and the rotation.
      const double step = 0.5 * (std::abs(c.gain_x) + std::abs(c.gain_y)) + 1e-6;
      EXPECT_NEAR(back.x, m.deflection_x[w], step) << "whisker " << w << " at " << f.utime;
      EXPECT_NEAR(back.y, m.deflection_y[w], step) << "whisker " << w << " at " << f.utime;
      ++r.compared;
    }
    r.contact_samples += contact;
  }
  EXPECT_EQ(assembler.total_gaps(), 0);
  EXPECT_EQ(assembler.incomplete(), 0);
  return r;
}

struct CandumpMode {
  const char* flag;
  wp::BusMode mode;
  int64_t period_us;
  int frames_per_board_sample;
};

class VitaSimCandump : public ::testing::TestWithParam<CandumpMode> {};

TEST_P(VitaSimCandump, DecodesBackToTheLogsWhiskerSamplesWithinOneCountAtTheBoardRate) {
  const CandumpMode& p = GetParam();
  const std::string world = contact_world();
  const std::string config = whiskerd_config();
  const std::string log = temp_path(std::string(p.flag) + ".lcmlog");
  const std::string candump = temp_path(std::string(p.flag) + ".candump");
  ASSERT_EQ(vita_sim("--world " + world + " --duration 4 --seed 9 -o " + log + " --candump " + candump +
                     " --whiskerd-config " + config + " --can-mode " + p.flag),
            0);
  const CandumpCheck r = check_candump(candump, log, config, p.mode);
  const int64_t board_samples = 4'000'000 / p.period_us;
  EXPECT_EQ(r.board_samples, 6 * board_samples);
  EXPECT_EQ(r.heartbeats, 6 * 40) << "10 Hz per board";
  EXPECT_EQ(r.frames, r.heartbeats + 6 * board_samples * p.frames_per_board_sample);
  for (const auto& times : r.sample_times) {
    ASSERT_EQ(static_cast<int64_t>(times.size()), board_samples);
    EXPECT_EQ(times.front(), SimParams{}.start_utime);
    for (std::size_t i = 1; i < times.size(); ++i) ASSERT_EQ(times[i] - times[i - 1], p.period_us);
  }
  EXPECT_GT(r.compared, 24 * board_samples * 9 / 10);
  EXPECT_GT(r.contact_samples, 10) << "the run must exercise real deflections, not only noise";
  fs::remove(world);
  fs::remove(config);
  fs::remove(log);
  fs::remove(candump);
}

INSTANTIATE_TEST_SUITE_P(Modes, VitaSimCandump,
                         ::testing::Values(CandumpMode{"fd", wp::BusMode::kFd, 2000, 1},
                                           CandumpMode{"classic", wp::BusMode::kClassic, 10000, 4}),
                         [](const auto& info) { return std::string(info.param.flag); });

TEST(VitaSim, SameSeedGivesAByteIdenticalCandumpWithOrWithoutTheLcmLog) {
  const std::string a = temp_path("a.candump");
  const std::string b = temp_path("b.candump");
  const std::string c = temp_path("c.candump");
  const std::string log = temp_path("ab.lcmlog");
  const std::string cfg = "--whiskerd-config " + test::source_path("config/whiskerd.yaml");
  ASSERT_EQ(vita_sim(arena() + " --duration 2 --seed 3 --candump " + a + " -o " + log + " " + cfg), 0);
  ASSERT_EQ(vita_sim(arena() + " --duration 2 --seed 3 --candump " + b + " " + cfg), 0);
  ASSERT_EQ(vita_sim(arena() + " --duration 2 --seed 4 --candump " + c + " " + cfg), 0);
  const std::string sa = slurp(a);
  EXPECT_GT(sa.size(), 100000u);
  EXPECT_TRUE(sa == slurp(b));
  EXPECT_FALSE(sa == slurp(c));
  // The installed config: FD at 500 Hz on can0.
  std::istringstream lines(sa);
  std::string first;
  std::getline(lines, first);
  EXPECT_EQ(first.substr(0, 31), "(1700000000.000000) can0 181##1");
  for (const auto& p : {a, b, c, log}) fs::remove(p);
}

TEST(VitaSim, CandumpFollowsTheWhiskerdConfigsModeRateIdsAndInterface) {
  const std::string config = temp_path("classic_whiskerd.yaml");
  std::ofstream(config) << "can:\n  interface: can7\n  mode: classic\n  rate_hz: 50\n"
                           "  ids: {sample_base: 0x280, heartbeat_base: 0x600}\n";
  const std::string out = temp_path("classic50.candump");
  ASSERT_EQ(vita_sim(arena() + " --duration 1 --candump " + out + " --whiskerd-config " + config), 0);
  std::ifstream in(out);
  std::map<uint32_t, std::vector<int64_t>> times;
  std::string line, iface;
  CanFrame f;
  while (std::getline(in, line)) {
    ASSERT_TRUE(parse_candump_line(line, f, iface)) << line;
    EXPECT_EQ(iface, "can7");
    EXPECT_FALSE(f.fd);
    times[f.id].push_back(f.utime);
  }
  ASSERT_EQ(times.size(), 12u);
  for (uint32_t id = 0x281; id <= 0x286; ++id) {
    ASSERT_EQ(times[id].size(), 50u * 4) << "50 Hz, four whisker frames per board sample";
    EXPECT_EQ(times[id][4] - times[id][0], 20000);
  }
  for (uint32_t id = 0x601; id <= 0x606; ++id) EXPECT_EQ(times[id].size(), 10u);
  fs::remove(config);
  fs::remove(out);
}

TEST(VitaSim, BadCandumpOptionsExitNonZero) {
  const std::string out = temp_path("bad.candump");
  const std::string bad_config = temp_path("bad_whiskerd.yaml");
  std::ofstream(bad_config) << "calibration:\n  default:\n    gain_z: 1\n";
  EXPECT_NE(vita_sim(arena() + " --duration 1 --candump " + out + " --whiskerd-config " + bad_config), 0);
  EXPECT_NE(vita_sim(arena() + " --duration 1 --candump " + out + " --whiskerd-config " + temp_path("missing.yaml")), 0);
  EXPECT_NE(vita_sim(arena() + " --duration 1 --candump " + out + " --can-mode flexray --whiskerd-config " +
                     test::source_path("config/whiskerd.yaml")),
            0);
  EXPECT_NE(vita_sim(arena() + " --duration 1 --candump /nonexistent/dir/x.candump --whiskerd-config " +
                     test::source_path("config/whiskerd.yaml")),
            0);
  fs::remove(bad_config);
  fs::remove(out);
}

}  // namespace
}  // namespace whiskeye::sim
