// The real LCM tools work with our types: udpm:// between processes, lcm-logger, our log reader on
// lcm-logger's files, lcm-logplayer, the generated Python modules, and lcm-spy (headless).
// Runs inside a private network namespace (NETNS in CMake), so no packet leaves the machine.
#include "samples.h"
#include "scratch.h"
#include "subprocess.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/clock.h"

#include <whiskeye/pose2d_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <thread>

namespace whiskeye {
namespace {

using testing::all_type_samples;
using testing::Subprocess;
using testing::wait_until;
namespace fs = std::filesystem;

// A send the kernel refuses (here: no route for multicast, as with the interface down) loses that
// message, is counted, and does not throw; sending works again once the route is back.
TEST(LcmBusSend, AFailedSendIsCountedNotThrown) {
  ASSERT_NE(std::getenv("WHISKEYE_NETNS"), nullptr) << "runs in its own network namespace (netns-run)";
  LcmBus bus;
  DecodeErrors errors;
  int received = 0;
  subscribe<pose2d_t>(bus, "SEND_TEST", [&](const pose2d_t&) { ++received; }, errors);
  ASSERT_EQ(std::system("ip route del 224.0.0.0/4 dev lo"), 0);
  for (int i = 0; i < 3; ++i) EXPECT_NO_THROW(publish(bus, "SEND_TEST", pose2d_t{}));
  EXPECT_EQ(bus.publish_errors(), 3);
  ASSERT_EQ(std::system("ip route add 224.0.0.0/4 dev lo"), 0);
  publish(bus, "SEND_TEST", pose2d_t{});
  EXPECT_EQ(bus.publish_errors(), 3);
  for (int i = 0; i < 20 && received == 0; ++i) bus.handle_timeout(50);
  EXPECT_EQ(received, 1);
}

class LcmTools : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::scratch_dir("lcm_tools_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  }

  // Starts an lcm_peer receiver and waits until it has subscribed.
  std::unique_ptr<Subprocess> start_receiver(double timeout_s) {
    auto rx = std::make_unique<Subprocess>(
        std::vector<std::string>{LCM_PEER, "receive", "--timeout", std::to_string(timeout_s)});
    EXPECT_TRUE(wait_until([&] { return rx->output().find("READY") != std::string::npos; }, 10.0))
        << rx->output();
    return rx;
  }

  // Records our traffic with the real lcm-logger and returns the log path. recording_start_us_ and
  // recording_end_us_ bracket the recording on the wall clock lcm-logger stamps events with.
  std::string record_with_lcm_logger() {
    const std::string log = (dir_ / "recorded.lcmlog").string();
    recording_start_us_ = now_utime();
    Subprocess logger({"lcm-logger", "-f", log});
    // lcm-logger prints nothing once subscribed; it opens the file first, so wait for the file and
    // then keep publishing until it has seen every type at least once.
    EXPECT_TRUE(wait_until([&] { return fs::exists(log); }, 10.0)) << logger.output();
    LcmBus bus;
    const auto samples = all_type_samples();
    std::uintmax_t round_bytes = 0;
    for (const auto& s : samples) round_bytes += s.bytes.size();
    // Rounds until the file holds more than two rounds' worth (so a whole round was logged however
    // late lcm-logger subscribed), then a few more.
    const bool logged = wait_until(
        [&] {
          for (const auto& s : samples) bus.publish_raw(s.channel, s.bytes);
          std::this_thread::sleep_for(std::chrono::milliseconds(25));
          return fs::file_size(log) > 2 * round_bytes;
        },
        20.0);
    EXPECT_TRUE(logged) << "lcm-logger wrote " << fs::file_size(log) << " bytes\n" << logger.output();
    for (int round = 0; round < 5; ++round) {
      for (const auto& s : samples) bus.publish_raw(s.channel, s.bytes);
      std::this_thread::sleep_for(std::chrono::milliseconds(25));
    }
    EXPECT_EQ(logger.stop(10.0, SIGINT), 0) << logger.output();
    recording_end_us_ = now_utime();
    return log;
  }

  fs::path dir_;
  int64_t recording_start_us_ = 0;
  int64_t recording_end_us_ = 0;
};

TEST_F(LcmTools, EveryTypeRoundTripsOverUdpmBetweenProcesses) {
  auto rx = start_receiver(15.0);
  LcmBus bus;
  const auto samples = all_type_samples();
  // UDP multicast: publish until the receiver has verified everything (or gives up).
  const bool done = wait_until(
      [&] {
        for (const auto& s : samples) bus.publish_raw(s.channel, s.bytes);
        return !rx->running();
      },
      20.0);
  ASSERT_TRUE(done) << rx->output();
  EXPECT_EQ(rx->wait(1.0), 0) << rx->output();
  for (const auto& s : samples) EXPECT_NE(rx->output().find("OK " + s.type + "\n"), std::string::npos) << s.type;
}

TEST_F(LcmTools, OurLogReaderReadsWhatLcmLoggerRecorded) {
  const std::string log = record_with_lcm_logger();
  std::map<std::string, const testing::TypeSample*> by_channel;
  const auto samples = all_type_samples();
  for (const auto& s : samples) by_channel[s.channel] = &s;
  std::set<std::string> seen;
  LogReader reader(log);
  LogEvent ev;
  // An event's utime is lcm-logger's receive time. It is not monotonic in file order (a message
  // of several UDP fragments can be stamped before a short one logged ahead of it: CI once saw
  // 152 us backwards), so it is checked against the recording's window, not against its neighbour.
  while (reader.next(ev)) {
    EXPECT_GE(ev.utime, recording_start_us_) << ev.channel << " stamped before lcm-logger started";
    EXPECT_LE(ev.utime, recording_end_us_) << ev.channel << " stamped after lcm-logger stopped";
    const auto it = by_channel.find(ev.channel);
    ASSERT_NE(it, by_channel.end()) << "unexpected channel " << ev.channel;
    EXPECT_TRUE(it->second->round_trips(ev.data)) << ev.channel;
    seen.insert(it->second->type);
  }
  EXPECT_EQ(seen.size(), samples.size());
}

TEST_F(LcmTools, LcmLogplayerReplaysARecordingToASubscriber) {
  const std::string log = record_with_lcm_logger();
  auto rx = start_receiver(30.0);
  Subprocess player({"lcm-logplayer", log});
  EXPECT_EQ(player.wait(30.0), 0) << player.output();
  EXPECT_EQ(rx->wait(10.0), 0) << rx->output();
}

TEST_F(LcmTools, GeneratedPythonModulesDecodeOurBytes) {
  Subprocess writer({LCM_PEER, "write-bytes", dir_.string()});
  ASSERT_EQ(writer.wait(10.0), 0) << writer.output();
  std::vector<std::string> argv{"python3", WHISKEYE_SOURCE_DIR "/tests/lcm/check_python_bindings.py", dir_.string()};
  for (const auto& s : all_type_samples()) argv.push_back(s.type);
  Subprocess py(argv, "", {"PYTHONPATH=" WHISKEYE_LCM_PYTHON_DIR});
  EXPECT_EQ(py.wait(30.0), 0) << py.output();
  for (const auto& s : all_type_samples()) EXPECT_NE(py.output().find("OK " + s.type), std::string::npos) << py.output();
}

TEST_F(LcmTools, LcmSpyStartsHeadlessAndFindsAllOurTypes) {
  // xvfb-run's own temp folder goes in a scratch folder: it is left behind when xvfb-run is stopped.
  Subprocess spy({"xvfb-run", "-a", WHISKEYE_SOURCE_DIR "/scripts/lcm-spy"}, "",
                 {"WHISKEYE_TYPES_JAR=" WHISKEYE_TYPES_JAR, "TMPDIR=" + whiskeye::testing::scratch_dir("lcm_spy")});
  const std::string expected = "Found " + std::to_string(all_type_samples().size()) + " LCM types";
  EXPECT_TRUE(wait_until([&] { return spy.output().find(expected) != std::string::npos; }, 60.0)) << spy.output();
  // Still running (the GUI came up under Xvfb) and no Java exception on the way.
  std::this_thread::sleep_for(std::chrono::seconds(2));
  EXPECT_TRUE(spy.running()) << spy.output();
  EXPECT_EQ(spy.output().find("Exception"), std::string::npos) << spy.output();
  spy.stop(5.0, SIGTERM);
}

TEST_F(LcmTools, LcmSpyWithoutADisplayFailsWithOneLineSayingSo) {
  // On the robot over plain ssh: not Java's page of AWT trace, one line and a non-zero exit.
  Subprocess spy({"env", "-u", "DISPLAY", "-u", "WAYLAND_DISPLAY", WHISKEYE_SOURCE_DIR "/scripts/lcm-spy"}, "",
                 {"WHISKEYE_TYPES_JAR=" WHISKEYE_TYPES_JAR});
  EXPECT_EQ(spy.wait(30.0), 1) << spy.output();
  const std::string out = spy.output();
  EXPECT_EQ(out.rfind("lcm-spy: no display (DISPLAY is not set)", 0), 0u) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
}

}  // namespace
}  // namespace whiskeye
