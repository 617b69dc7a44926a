// vita-sim's candump log read by the real can-utils (log2long, log2asc): the tools that parse the
// `candump -l` format without a CAN device accept every line as the frame vita-sim meant.
#include "sim_test_util.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace whiskeye::sim {
namespace {

namespace fs = std::filesystem;

std::string temp_path(const std::string& name) {
  return (fs::temp_directory_path() / ("candump_tools_" + std::to_string(getpid()) + "_" + name)).string();
}

// Runs a shell command, returns its stdout; `status` gets the exit code.
std::string run(const std::string& cmd, int& status) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int s = pclose(p);
  status = WIFEXITED(s) ? WEXITSTATUS(s) : -1;
  return out;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::string make_candump(const std::string& mode) {
  const std::string path = temp_path(mode + ".candump");
  int status = -1;
  run(std::string(VITA_SIM_EXE) + " --robot " + test::source_path("config/robot.yaml") + " --world " +
          test::source_path("config/worlds/aliased_arena.yaml") + " --whiskerd-config " +
          test::source_path("config/whiskerd.yaml") + " --duration 1 --seed 2 --can-mode " + mode + " --candump " +
          path + " -q 2>&1",
      status);
  EXPECT_EQ(status, 0);
  return path;
}

TEST(CandumpCanUtils, Log2longReadsEveryFdFrameWithItsLength) {
  const std::string path = make_candump("fd");
  int status = -1;
  const std::vector<std::string> lines = lines_of(run(std::string(LOG2LONG) + " < " + path, status));
  ASSERT_EQ(status, 0);
  // 1 s: 500 samples x 6 boards (32 bytes) + 10 heartbeats x 6 boards (2 bytes).
  ASSERT_EQ(lines.size(), 3000u + 60u);
  std::map<std::string, int> by_length;
  for (const std::string& l : lines) {
    const auto open = l.find('[');
    ASSERT_NE(open, std::string::npos) << l;
    ++by_length[l.substr(open, l.find(']') - open + 1)];
  }
  EXPECT_EQ(by_length["[32]"], 3000);
  EXPECT_EQ(by_length["[2]"], 60);
  // Its rendering of the first frame: time, interface, id, length, the seq 0 and a zero status.
  EXPECT_EQ(lines[0].substr(0, 54), "(1700000000.000000)  can0       181  [32]  00 00 00 00");
  int heartbeats_board5 = 0;
  for (const std::string& l : lines) heartbeats_board5 += l.find(" 706   [2]  05 00 ") != std::string::npos;
  EXPECT_EQ(heartbeats_board5, 10) << "board 5 operational at 10 Hz";
  fs::remove(path);
}

TEST(CandumpCanUtils, Log2ascSeesCanFdFramesWithBitRateSwitchAndClassicHeartbeats) {
  const std::string path = make_candump("fd");
  int status = -1;
  const std::vector<std::string> lines = lines_of(run(std::string(LOG2ASC) + " -I " + path + " can0", status));
  ASSERT_EQ(status, 0);
  int fd = 0, classic = 0;
  for (const std::string& l : lines) {
    if (l.find(" CANFD ") != std::string::npos) {
      ++fd;
      // "... Rx <id> <name> BRS ESI DLC len ...": BRS 1, ESI 0, DLC d = 32 bytes.
      EXPECT_NE(l.find(" 1 0 d 32 "), std::string::npos) << l;
    } else if (l.find(" Rx ") != std::string::npos) {
      ++classic;
      EXPECT_NE(l.find(" d 2 05 00"), std::string::npos) << l;
    }
  }
  EXPECT_EQ(fd, 3000);
  EXPECT_EQ(classic, 60);
  fs::remove(path);
}

TEST(CandumpCanUtils, Log2longReadsClassicFramesFourPerBoardSample) {
  const std::string path = make_candump("classic");
  int status = -1;
  const std::vector<std::string> lines = lines_of(run(std::string(LOG2LONG) + " < " + path + " | grep -c ' \\[8\\] '", status));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], std::to_string(100 * 6 * 4));  // 100 Hz x 6 boards x 4 whiskers
  fs::remove(path);
}

}  // namespace
}  // namespace whiskeye::sim
