// A vita-sim log played by the real lcm-logplayer over udpm:// is received and decoded by an LcmBus
// subscriber (run inside a private network namespace).
#include "whiskeye/common/bus.h"

#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>

extern char** environ;

namespace whiskeye {
namespace {

TEST(VitaSimReplay, LcmLogplayerReplaysTheLogToAnLcmSubscriber) {
  const std::string log = (std::filesystem::temp_directory_path() / ("vita_sim_replay_" + std::to_string(getpid()) + ".lcmlog")).string();
  const std::string cmd = std::string(VITA_SIM_EXE) + " --world " WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml --robot " WHISKEYE_SOURCE_DIR
                          "/config/robot.yaml --duration 1 -q -o " + log + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0);

  // Camera frames are 614 KB: a receive buffer larger than the kernel default (rmem_max is 4 MB here).
  const std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
  LcmBus bus(url);
  DecodeErrors errors;
  int samples = 0;
  int odometry = 0;
  int images = 0;
  int64_t last_seq = 0;
  subscribe<whisker_sample_t>(bus, "WHISKER_SAMPLE", [&](const whisker_sample_t& m) {
    EXPECT_EQ(m.num_whiskers, 24);
    EXPECT_GT(m.seq, last_seq);
    last_seq = m.seq;
    ++samples;
  }, errors);
  subscribe<odometry_t>(bus, "ODOMETRY", [&](const odometry_t&) { ++odometry; }, errors);
  subscribe<image_t>(bus, "CAMERA", [&](const image_t& m) {
    EXPECT_EQ(m.size, 640 * 480 * 2);
    ++images;
  }, errors);

  std::string url_arg = "--lcm-url=" + url;
  std::vector<char*> argv{const_cast<char*>(LCM_LOGPLAYER), url_arg.data(), const_cast<char*>(log.c_str()), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, LCM_LOGPLAYER, nullptr, nullptr, argv.data(), environ), 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  int status = 0;
  bool exited = false;
  while (std::chrono::steady_clock::now() < deadline) {
    bus.handle_timeout(50);
    if (!exited && waitpid(pid, &status, WNOHANG) == pid) exited = true;
    if (exited && bus.handle_timeout(200) == 0) break;  // drained
  }
  if (!exited) {
    kill(pid, SIGTERM);
    waitpid(pid, &status, 0);
  }
  std::filesystem::remove(log);
  EXPECT_TRUE(exited) << "lcm-logplayer did not finish";
  EXPECT_EQ(errors.total(), 0);
  // 1 s of log: 500 samples, 50 odometry, 5 frames; loopback UDP may drop a little under load.
  EXPECT_GE(samples, 450);
  EXPECT_GE(odometry, 45);
  EXPECT_GE(images, 3);
}

}  // namespace
}  // namespace whiskeye
