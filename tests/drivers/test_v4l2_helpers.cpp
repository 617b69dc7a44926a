// V4L2 capture helpers that need no device (real capture is tested against vivid in the VM:
// tests/vm/scenario_camerad.sh).
#include <gtest/gtest.h>

#include "whiskeye/drivers/v4l2_capture.h"

using namespace whiskeye::v4l2;

TEST(V4l2Helpers, FourccMatchesTheLcmConstants) {
  // image_t.PIXEL_FORMAT_YUYV / MJPEG / GREY
  EXPECT_EQ(kYUYV, 1448695129u);
  EXPECT_EQ(kMJPG, 1196444237u);
  EXPECT_EQ(kGREY, 1497715271u);
  EXPECT_EQ(fourcc_name(kYUYV), "YUYV");
  EXPECT_EQ(fourcc_from_name("MJPG"), kMJPG);
  EXPECT_EQ(fourcc_from_name("YUV"), 0u);
}

TEST(V4l2Helpers, MonotonicTimestampBecomesEpochUtime) {
  // Frame captured 30 ms before "now" on the monotonic clock -> 30 ms before now on the epoch.
  EXPECT_EQ(monotonic_to_utime(1'000'000, 1'030'000, 1'700'000'000'030'000), 1'700'000'000'000'000);
}

TEST(V4l2Helpers, ReopenBackoffDoublesUpToTheCapAndResets) {
  Backoff b(0.2, 1.0);
  EXPECT_DOUBLE_EQ(b.next(), 0.2);
  EXPECT_DOUBLE_EQ(b.next(), 0.4);
  EXPECT_DOUBLE_EQ(b.next(), 0.8);
  EXPECT_DOUBLE_EQ(b.next(), 1.0);
  EXPECT_DOUBLE_EQ(b.next(), 1.0);
  b.reset();
  EXPECT_DOUBLE_EQ(b.next(), 0.2);
}

TEST(V4l2Capture, MissingDeviceIsReportedAsGoneNamingTheDevice) {
  CaptureConfig c;
  c.device = "/dev/video_does_not_exist";
  try {
    Capture cap(c, [](const std::string&) {});
    FAIL();
  } catch (const CaptureError& e) {
    EXPECT_TRUE(e.device_gone());
    EXPECT_NE(std::string(e.what()).find("/dev/video_does_not_exist"), std::string::npos);
  }
}

TEST(V4l2Capture, NonVideoDeviceIsRejected) {
  CaptureConfig c;
  c.device = "/dev/null";
  EXPECT_THROW(Capture(c, [](const std::string&) {}), CaptureError);
}

TEST(V4l2Capture, NoMatchingCardIsAnError) {
  CaptureConfig c;
  c.match_card = "no-such-camera-model";
  EXPECT_THROW(find_device(c), CaptureError);
}
