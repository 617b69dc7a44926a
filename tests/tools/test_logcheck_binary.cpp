// whiskeye-logcheck on a simulator recording, whole and with messages cut out of it.
#include "scratch.h"
#include "subprocess.h"

#include "whiskeye/common/bus.h"

#include <gtest/gtest.h>

#include <fstream>

#include <sys/stat.h>

namespace whiskeye {
namespace {

using testing::Subprocess;

class LogcheckBinary : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    log_ = testing::scratch_file("logcheck_sim", ".lcmlog");
    Subprocess sim({VITA_SIM_EXE, "--world", WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml", "--robot",
                    WHISKEYE_SOURCE_DIR "/config/robot.yaml", "--duration", "3", "--seed", "1", "--quiet", "--output",
                    log_});
    ASSERT_EQ(sim.wait(60), 0) << sim.output();
  }
  static std::string log_;
};
std::string LogcheckBinary::log_;

TEST_F(LogcheckBinary, AWholeRecordingLostNothing) {
  Subprocess check({LOGCHECK_EXE, log_});
  ASSERT_EQ(check.wait(30), 0) << check.output();
  const std::string out = check.output();
  EXPECT_NE(out.find("nothing lost on the 4 channel(s) with sequence numbers"), std::string::npos) << out;
  EXPECT_NE(out.find("WHISKER_SAMPLE            1500"), std::string::npos) << out;
}

TEST_F(LogcheckBinary, MessagesCutOutOfARecordingAreCountedAndFailIt) {
  // As lcm-logger under load: 104 whisker samples in a row and 2 camera frames never written.
  const std::string cut = testing::scratch_file("logcheck_cut", ".lcmlog");
  {
    LogReader reader(log_);
    LogWriterBus writer(cut);
    LogEvent ev;
    int samples = 0, frames = 0;
    while (reader.next(ev)) {
      if (ev.channel == "WHISKER_SAMPLE" && ++samples > 500 && samples <= 604) continue;
      if (ev.channel == "CAMERA" && (++frames == 3 || frames == 9)) continue;
      writer.set_time(ev.utime);
      writer.publish_raw(ev.channel, ev.data);
    }
  }
  Subprocess check({LOGCHECK_EXE, cut});
  EXPECT_EQ(check.wait(30), 1) << check.output();
  const std::string out = check.output();
  EXPECT_NE(out.find("lost CAMERA 2 of 15 (13.33 %, at most 1 in a row), WHISKER_SAMPLE 104 of 1500 (6.93 %, at most "
                     "104 in a row)"),
            std::string::npos)
      << out;
  // Below the threshold: reported, and not a failure.
  Subprocess lenient({LOGCHECK_EXE, cut, "--max-loss", "0.2"});
  EXPECT_EQ(lenient.wait(30), 0) << lenient.output();
}

TEST_F(LogcheckBinary, ABadCommandLineOrAMissingFileIsOneLine) {
  Subprocess bad({LOGCHECK_EXE, log_, "--max-loss", "2"});
  EXPECT_EQ(bad.wait(10), 2) << bad.output();
  EXPECT_EQ(bad.output().rfind("whiskeye-logcheck: ", 0), 0u) << bad.output();
  Subprocess missing({LOGCHECK_EXE, "/nonexistent/run.lcmlog"});
  EXPECT_EQ(missing.wait(10), 1) << missing.output();
  EXPECT_EQ(missing.output().rfind("whiskeye-logcheck: ", 0), 0u) << missing.output();
  EXPECT_NE(missing.output().find("/nonexistent/run.lcmlog"), std::string::npos) << missing.output();
}

TEST_F(LogcheckBinary, AnEmptyLogOrOneWithoutASingleEventIsSaidSoAndFails) {
  const std::string empty = testing::scratch_file("logcheck_empty", ".lcmlog");
  std::ofstream(empty).close();
  Subprocess e({LOGCHECK_EXE, empty});
  EXPECT_EQ(e.wait(10), 1) << e.output();
  EXPECT_NE(e.output().find(empty + ": the log is empty (0 bytes): nothing was recorded"), std::string::npos) << e.output();
  EXPECT_EQ(e.output().find("nothing lost"), std::string::npos) << e.output();

  const std::string garbage = testing::scratch_file("logcheck_garbage", ".lcmlog");
  std::ofstream(garbage) << std::string(1000, 'x');
  Subprocess g({LOGCHECK_EXE, garbage});
  EXPECT_EQ(g.wait(10), 1) << g.output();
  EXPECT_NE(g.output().find(garbage + ": no event could be read from its 1000 bytes"), std::string::npos) << g.output();
}

TEST_F(LogcheckBinary, AFifoWithoutAWriterIsRefusedAtOnce) {
  const std::string fifo = testing::scratch_file("logcheck_fifo", ".lcmlog");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  Subprocess check({LOGCHECK_EXE, fifo});
  EXPECT_EQ(check.wait(20), 1) << "waited for a writer: " << check.output();
  EXPECT_NE(check.output().find(fifo + ": cannot open the LCM log for reading: not a regular file"), std::string::npos)
      << check.output();
}

}  // namespace
}  // namespace whiskeye
