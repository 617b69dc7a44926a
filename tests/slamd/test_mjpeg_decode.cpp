// slamd's MJPEG decoder (whiskeye/slamd/mjpeg_decode.h) against hostile frames, run on the real
// libjpeg-turbo: frames of the project's encoders with markers and segments spliced in code
// (tests/support/hostile_jpeg.h), each next to the frame it was made from, which decodes.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <string>
#include <vector>

#include "whiskeye/slamd/mjpeg_decode.h"
#include "hostile_jpeg.h"
#include "mjpeg_pattern.h"

using namespace whiskeye;
using slam::InputError;

namespace {

// The reason check_mjpeg_frame() gives, "" when it takes the frame.
std::string check_reason(const std::vector<uint8_t>& jpeg, int width, int height) {
  try {
    slamd::check_mjpeg_frame(jpeg, width, height);
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

// The reason decode_mjpeg_grey() gives, "" when it decodes the frame.
std::string decode_reason(const std::vector<uint8_t>& jpeg, int width, int height) {
  std::vector<uint8_t> grey(static_cast<std::size_t>(width) * height);
  try {
    slamd::decode_mjpeg_grey(jpeg, width, height, grey.data(), static_cast<std::size_t>(width));
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

// This process's peak resident set so far, in MB.
long peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024;
}

const std::vector<uint8_t>& camera_frame() {
  static const std::vector<uint8_t> f = test::mjpeg_pattern_jpeg(640, 480, 52);
  return f;
}

TEST(MjpegDecode, ACameraFrameIsCheckedAndDecoded) {
  EXPECT_EQ(check_reason(camera_frame(), 640, 480), "");
  EXPECT_EQ(decode_reason(camera_frame(), 640, 480), "");
  EXPECT_EQ(check_reason(camera_frame(), 320, 240), "image: MJPEG frame is 640x480 by its JPEG header, the message says 320x240");
}

// FF 00 after SOI: a marker walk that takes it for a segment (jpeg::frame_size did) jumps into an
// APP1 holding a 640x480 frame header, which libjpeg skips; libjpeg reads the frame behind it.
// Checked against that walk's 640x480, the frame passed, and libjpeg allocated 2 GB for its hidden
// 32000 x 32000 progressive header before the decoder saw the size it decodes (peak RSS 4 MB ->
// 2.0 GB). The size checked is now the one libjpeg parsed, before it allocates for the image.
TEST(MjpegDecode, TheSizeCheckedIsTheHeaderLibjpegDecodesNotWhatAnotherParserReads) {
  const std::vector<uint8_t> hostile = test::camera_frame_hiding_progressive(640, 480, 32000, 32000);
  const long rss_before = peak_rss_mb();
  const std::string says = "image: MJPEG frame is 32000x32000 by its JPEG header, the message says 640x480";
  EXPECT_EQ(check_reason(hostile, 640, 480), says);
  EXPECT_EQ(decode_reason(hostile, 640, 480), says);
  EXPECT_LT(peak_rss_mb() - rss_before, 64) << "MB more at the peak: libjpeg allocated for the hidden header";
  // Hiding a frame of the message's size does not pass either: libjpeg warned of the bytes it skipped.
  EXPECT_EQ(check_reason(test::hide_frame_behind(camera_frame(), camera_frame()), 640, 480),
            "image: MJPEG frame is damaged (Corrupt JPEG data: 4 extraneous bytes before marker 0xe1)");
}

}  // namespace
