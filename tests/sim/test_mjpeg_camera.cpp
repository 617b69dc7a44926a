// vita-sim --camera-format mjpeg end to end: the CAMERA frames are whole JPEGs carrying the fields
// camerad gives an MJPEG frame, they decode with slamd's own decoder to the frames the YUYV run of the
// same seed carries, and slamd --replay runs the SLAM on such a log as on the YUYV one.
#include "subprocess.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/slamd/mjpeg_decode.h"

#include <whiskeye/image_t.hpp>
#include <whiskeye/slam_status_t.hpp>
#include <whiskeye/vita_event_t.hpp>

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace whiskeye {
namespace {

namespace fs = std::filesystem;
using testing::Subprocess;

class MjpegCamera : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // ctest runs each test in its own process, concurrently: one directory per process.
    dir_ = fs::path(::testing::TempDir()) / ("sim_mjpeg_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  // vita-sim on the default arena; returns the log's path.
  static std::string simulate(const std::string& name, std::vector<std::string> extra) {
    const std::string out = (dir_ / name).string();
    std::vector<std::string> argv{VITA_SIM_EXE, "--world", WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml",
                                  "--robot",    WHISKEYE_SOURCE_DIR "/config/robot.yaml", "--quiet", "--output", out};
    argv.insert(argv.end(), extra.begin(), extra.end());
    Subprocess sim(argv);
    EXPECT_EQ(sim.wait(120), 0) << sim.output();
    return out;
  }

  static fs::path dir_;
};
fs::path MjpegCamera::dir_;

std::vector<image_t> camera_frames(const std::string& path) {
  std::vector<image_t> frames;
  LogReader log(path);
  LogEvent e;
  while (log.next(e)) {
    if (e.channel != "CAMERA") continue;
    image_t img;
    EXPECT_TRUE(decode_message(std::span<const uint8_t>(e.data), img)) << path;
    frames.push_back(std::move(img));
  }
  return frames;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Mean absolute difference between a decoded JPEG and the Y bytes of the same YUYV frame.
double mean_difference_to_luma(const image_t& jpeg, const image_t& yuyv) {
  std::vector<uint8_t> grey(static_cast<std::size_t>(jpeg.width) * jpeg.height);
  slamd::decode_mjpeg_grey(jpeg.data, jpeg.width, jpeg.height, grey.data(), static_cast<std::size_t>(jpeg.width));
  double sum = 0;
  for (int y = 0; y < yuyv.height; ++y) {
    for (int x = 0; x < yuyv.width; ++x) {
      sum += std::abs(grey[static_cast<std::size_t>(y) * jpeg.width + x] -
                      yuyv.data[static_cast<std::size_t>(y) * yuyv.row_stride + 2 * x]);
    }
  }
  return sum / static_cast<double>(grey.size());
}

TEST_F(MjpegCamera, FramesAreWholeJpegsWithCamerasFieldsDecodingToTheYuyvRunsLuma) {
  const auto yuyv = camera_frames(simulate("yuyv.lcmlog", {"--duration", "2", "--seed", "3"}));
  const auto mjpeg = camera_frames(simulate("mjpeg.lcmlog", {"--duration", "2", "--seed", "3", "--camera-format", "mjpeg"}));
  ASSERT_EQ(mjpeg.size(), 10u) << "5 fps";
  ASSERT_EQ(yuyv.size(), mjpeg.size());
  for (std::size_t i = 0; i < mjpeg.size(); ++i) {
    const image_t& m = mjpeg[i];
    SCOPED_TRACE("frame " + std::to_string(i));
    EXPECT_EQ(m.utime, yuyv[i].utime);
    EXPECT_EQ(m.seq, yuyv[i].seq);
    EXPECT_EQ(m.pixelformat, image_t::PIXEL_FORMAT_MJPEG);
    EXPECT_EQ(m.width, 640);
    EXPECT_EQ(m.height, 480);
    EXPECT_EQ(m.row_stride, 0) << "as camerad publishes a compressed frame";
    EXPECT_EQ(m.size, static_cast<int32_t>(m.data.size()));
    EXPECT_LT(m.data.size(), 640u * 480 * 2 / 8) << "a tenth of YUYV's bytes or less";
    ASSERT_GE(m.data.size(), 4u);
    EXPECT_EQ(m.data[0], 0xFF);
    EXPECT_EQ(m.data[1], 0xD8) << "start of image";
    EXPECT_NO_THROW(slamd::check_mjpeg_frame(m.data, m.width, m.height));
    // Quality 85 on a noisy image: within about a grey level on average.
    EXPECT_LT(mean_difference_to_luma(m, yuyv[i]), 2.0);
  }
}

TEST_F(MjpegCamera, SameSeedGivesAByteIdenticalLogAndQualitySetsTheTradeOff) {
  const std::string a = simulate("a.lcmlog", {"--duration", "1", "--seed", "4", "--camera-format", "mjpeg"});
  const std::string b = simulate("b.lcmlog", {"--duration", "1", "--seed", "4", "--camera-format", "MJPEG"});
  EXPECT_TRUE(slurp(a) == slurp(b));
  const auto yuyv = camera_frames(simulate("q_yuyv.lcmlog", {"--duration", "1", "--seed", "4"}));
  const auto q50 = camera_frames(simulate("q50.lcmlog", {"--duration", "1", "--seed", "4", "--camera-format", "mjpeg",
                                                         "--jpeg-quality", "50"}));
  const auto q95 = camera_frames(simulate("q95.lcmlog", {"--duration", "1", "--seed", "4", "--camera-format", "mjpeg",
                                                         "--jpeg-quality", "95"}));
  ASSERT_EQ(q50.size(), 5u);
  ASSERT_EQ(q95.size(), 5u);
  ASSERT_EQ(yuyv.size(), 5u);
  for (std::size_t i = 0; i < q50.size(); ++i) {
    EXPECT_LT(q50[i].data.size(), q95[i].data.size());
    EXPECT_GT(mean_difference_to_luma(q50[i], yuyv[i]), mean_difference_to_luma(q95[i], yuyv[i]));
  }
  Subprocess bad({VITA_SIM_EXE, "--world", WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml", "--robot",
                  WHISKEYE_SOURCE_DIR "/config/robot.yaml", "--duration", "1", "--camera-format", "mjpeg",
                  "--jpeg-quality", "0", "--output", (dir_ / "bad.lcmlog").string()});
  EXPECT_EQ(bad.wait(30), 2);
  EXPECT_NE(bad.output().find("--jpeg-quality"), std::string::npos) << bad.output();
}

struct Replayed {
  std::vector<vita_event_t> events;
  slam_status_t status;  // the last SLAM_STATUS
};

Replayed replay(const std::string& log, const std::string& out, const std::string& mode) {
  Subprocess slamd({SLAMD_EXE, "--replay", log, "--output", out, "--mode", mode, "--config",
                    WHISKEYE_SOURCE_DIR "/config/slam.yaml", "--robot", WHISKEYE_SOURCE_DIR "/config/robot.yaml"});
  EXPECT_EQ(slamd.wait(120), 0) << slamd.output();
  Replayed r;
  LogReader reader(out);
  LogEvent e;
  while (reader.next(e)) {
    if (e.channel == "VITA_EVENT") {
      vita_event_t m;
      EXPECT_TRUE(decode_message(std::span<const uint8_t>(e.data), m));
      r.events.push_back(m);
    } else if (e.channel == "SLAM_STATUS") {
      EXPECT_TRUE(decode_message(std::span<const uint8_t>(e.data), r.status));
    }
  }
  return r;
}

TEST_F(MjpegCamera, SlamdReplaysAnMjpegLogAsItReplaysTheYuyvLogOfTheSameSeed) {
  // A lap and a quarter: the start is seen again, so vision closes loops.
  const std::string yuyv_log = simulate("slam_yuyv.lcmlog", {"--duration", "80", "--seed", "2"});
  const std::string mjpeg_log = simulate("slam_mjpeg.lcmlog", {"--duration", "80", "--seed", "2", "--camera-format", "mjpeg"});
  EXPECT_LT(fs::file_size(mjpeg_log) * 3, fs::file_size(yuyv_log));
  for (const std::string mode : {"visual", "vita"}) {
    SCOPED_TRACE(mode);
    const Replayed y = replay(yuyv_log, (dir_ / ("out_yuyv_" + mode)).string(), mode);
    const Replayed m = replay(mjpeg_log, (dir_ / ("out_mjpeg_" + mode)).string(), mode);
    // Every frame decoded and used: none refused, no cycle without its frame.
    EXPECT_EQ(m.status.decode_errors, 0);
    EXPECT_EQ(m.status.validation_errors, 0);
    EXPECT_EQ(m.status.cycles_without_camera, y.status.cycles_without_camera);
    EXPECT_EQ(m.status.cycles, y.status.cycles);
    ASSERT_GE(m.events.size(), 70u);
    ASSERT_EQ(m.events.size(), y.events.size());
    // The same decisions, cycle by cycle, but for the odd match JPEG's loss tips over.
    int same = 0;
    int relocalised = 0;
    for (std::size_t i = 0; i < m.events.size(); ++i) {
      same += m.events[i].type == y.events[i].type && m.events[i].to_id == y.events[i].to_id;
      relocalised += m.events[i].type == vita_event_t::RELOCALISE;
    }
    EXPECT_GE(same * 10, static_cast<int>(m.events.size()) * 9);
    if (mode == "visual") {
      EXPECT_GE(relocalised, 1) << "vision closes the loop on an MJPEG log";
    }
  }
}

}  // namespace
}  // namespace whiskeye
