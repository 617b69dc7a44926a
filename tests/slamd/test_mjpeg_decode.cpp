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

std::vector<uint8_t> pattern_jpeg(test::ScanLayout layout) {
  return test::encode_jpeg_scans(test::mjpeg_pattern(640, 480, 52), 640, 480, 640, layout);
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

// A progressive frame is decoded from all its scans into a whole-image buffer before its first row:
// 15,000 repeated scans of AC coefficients (35 bytes each, no warning: libjpeg's progression checks
// let them follow one another) took 18-30 s at 4096 x 4096, 0.84-1.5 s at 640 x 480 with 40,000, and
// were taken as a template. No camera sends one: refused from its header, before any scan is read.
TEST(MjpegDecode, AProgressiveFrameIsRefusedByItsHeaderHoweverFewItsScans) {
  const std::string says =
      "image: MJPEG frame is a progressive JPEG; only baseline JPEG (one sequential, Huffman-coded scan) is decoded, "
      "as a camera sends it";
  const std::vector<uint8_t> progressive = pattern_jpeg(test::ScanLayout::kProgressive);
  EXPECT_EQ(check_reason(progressive, 640, 480), says);
  EXPECT_EQ(decode_reason(progressive, 640, 480), says);
  const std::vector<uint8_t> scans = test::progressive_with_repeated_scans(640, 480, 40'000);
  EXPECT_EQ(check_reason(scans, 640, 480), says);
  EXPECT_EQ(decode_reason(scans, 640, 480), says);
}

// Sequential frames can hold many scans too (one component in each: then every block of a repeated
// one is decoded again, 1.5 ms a scan at 640 x 480) and arithmetic coding, which no camera uses.
TEST(MjpegDecode, AFrameWithSeveralScansOrArithmeticCodingIsRefusedByItsHeader) {
  const std::string baseline = "; only baseline JPEG (one sequential, Huffman-coded scan) is decoded, as a camera sends it";
  const std::vector<uint8_t> per_component = pattern_jpeg(test::ScanLayout::kScanPerComponent);
  const std::string scans = "image: MJPEG frame has its 3 components in several scans (1 in the first)" + baseline;
  EXPECT_EQ(check_reason(per_component, 640, 480), scans);
  EXPECT_EQ(decode_reason(test::with_repeated_last_scan(per_component, 1000), 640, 480), scans);
  EXPECT_EQ(check_reason(pattern_jpeg(test::ScanLayout::kArithmetic), 640, 480),
            "image: MJPEG frame is arithmetic-coded" + baseline);
}

// In a frame whose first scan holds every component libjpeg refuses a second scan itself: what
// keeps a baseline frame's decode to one pass (libjpeg-turbo 2.1 behaviour, pinned).
TEST(MjpegDecode, ABaselineFrameWithMoreScansAppendedIsRefusedByLibjpeg) {
  const std::vector<uint8_t> more = test::with_repeated_last_scan(camera_frame(), 100);
  EXPECT_EQ(check_reason(more, 640, 480), "") << "its header is a camera's";
  EXPECT_EQ(decode_reason(more, 640, 480), "image: MJPEG frame does not decode: Didn't expect more than one scan");
}

}  // namespace
