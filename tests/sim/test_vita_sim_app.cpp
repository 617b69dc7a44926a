// vita-sim's options and modes run in-process (vita_sim_app.h): the exit statuses and outputs a
// command line selects, and the summary line of an injected fault.
#include "whiskeye/sim/vita_sim_app.h"

#include "sim_test_util.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

namespace whiskeye::sim {
namespace {

namespace fs = std::filesystem;

std::string temp_path(const std::string& name) {
  return (fs::temp_directory_path() / ("vita_sim_app_test_" + std::to_string(getpid()) + "_" + name)).string();
}

// vita-sim's main, with `args` after the robot geometry and the default arena.
int vita_sim(std::vector<std::string> args) {
  args.insert(args.begin(), {"vita-sim", "--robot", test::source_path("config/robot.yaml"), "--world",
                             test::source_path("config/worlds/aliased_arena.yaml"), "-q"});
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  cli::Program program("vita-sim", "test");
  VitaSimOptions options;
  add_vita_sim_options(program, options);
  return program.run(static_cast<int>(argv.size()), argv.data(), [&] { return run_vita_sim(program.app(), options); });
}

TEST(VitaSimApp, OptionsBeyondTheWorldsBoundsExitWith2) {
  const std::string log = temp_path("x.lcmlog");
  EXPECT_EQ(vita_sim({"--laps", "0", "-o", log}), 2);
  EXPECT_EQ(vita_sim({"--duration", "-1", "-o", log}), 2);
  EXPECT_EQ(vita_sim({"--start-phase", "7", "-o", log}), 2);
  EXPECT_EQ(vita_sim({"--start-utime", "-5", "-o", log}), 2);
  EXPECT_EQ(vita_sim({}), 2) << "no output";
  EXPECT_FALSE(fs::exists(log));
}

TEST(VitaSimApp, PlotsAloneSimulateNothing) {
  const std::string png = temp_path("world.png");
  ASSERT_EQ(vita_sim({"--plot-world", png}), 0);
  EXPECT_GT(fs::file_size(png), 1000u);
  fs::remove(png);
}

TEST(VitaSimApp, FaultSummarySaysWhatWhenAndWhatItTouched) {
  FaultRecord board;
  board.kind = FaultKind::BoardOffline;
  board.index = 2;
  board.began_utime = 1'001'500'000;
  board.ended_utime = 1'003'500'000;
  board.affected = 1000;
  EXPECT_EQ(fault_summary(board, 1'000'000'000),
            "fault board_offline board 2: 1.500 s to 3.500 s, 1000 board samples stale (4 whiskers STATUS_STALE)");
  FaultRecord kidnap;
  kidnap.kind = FaultKind::Kidnap;
  kidnap.value = kPi / 2;
  EXPECT_EQ(fault_summary(kidnap, 0), "fault kidnap to polar angle 90.0 deg: not reached (the run ended first)");
}

}  // namespace
}  // namespace whiskeye::sim
