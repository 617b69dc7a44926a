// The vita-sim executable: reproducible logs, channels and rates in the log, time order, errors.
#include "sim_test_util.h"

#include "whiskeye/common/bus.h"

#include <whiskeye/contact_truth_t.hpp>
#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

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

TEST(VitaSim, BadInputExitsNonZero) {
  const std::string bad = temp_path("bad.yaml");
  std::ofstream(bad) << "world:\n  walls: [{from: [0, 0], to: [1, 0], pattern: missing}]\n";
  EXPECT_NE(vita_sim("--world " + bad + " -o " + temp_path("x.lcmlog")), 0);
  EXPECT_NE(vita_sim(arena()), 0);  // no output
  fs::remove(bad);
}

}  // namespace
}  // namespace whiskeye::sim
