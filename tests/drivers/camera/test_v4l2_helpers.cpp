// V4L2 capture helpers that need no device (real capture is tested against vivid in the VM:
// tests/vm/scenario_camerad.sh).
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "hostile_jpeg.h"
#include "mjpeg_pattern.h"
#include "whiskeye/camera/v4l2_capture.h"

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

// The mapped length of each test buffer: larger than any frame below.
constexpr std::size_t kMapped = 1 << 20;

TEST(V4l2FrameCheck, WholeFramesAreUsable) {
  // 640x480 YUYV: stride 1280, 614400 bytes; GREY: stride 640; MJPG: any non-empty size.
  EXPECT_EQ(check_frame(0, 614400, kMapped, kYUYV, 1280, 480), FrameCheck::kUsable);
  EXPECT_EQ(check_frame(0, 700000, kMapped, kYUYV, 1280, 480), FrameCheck::kUsable);  // driver padding
  EXPECT_EQ(check_frame(0, 307200, kMapped, kGREY, 640, 480), FrameCheck::kUsable);
  EXPECT_EQ(check_frame(0, 23456, kMapped, kMJPG, 0, 480), FrameCheck::kUsable);
  EXPECT_EQ(check_frame(~kBufFlagError, 614400, kMapped, kYUYV, 1280, 480), FrameCheck::kUsable);  // other flags
}

TEST(V4l2FrameCheck, BufferFlaggedAsErrorIsSkippedWhateverItsSize) {
  EXPECT_EQ(check_frame(kBufFlagError, 614400, kMapped, kYUYV, 1280, 480), FrameCheck::kErrorFlag);
  EXPECT_EQ(check_frame(kBufFlagError | 0x1, 23456, kMapped, kMJPG, 0, 480), FrameCheck::kErrorFlag);
}

TEST(V4l2FrameCheck, TruncatedRawFrameIsSkipped) {
  EXPECT_EQ(check_frame(0, 614399, kMapped, kYUYV, 1280, 480), FrameCheck::kShortPayload);
  EXPECT_EQ(check_frame(0, 1280 * 240, kMapped, kYUYV, 1280, 480), FrameCheck::kShortPayload);
  EXPECT_EQ(check_frame(0, 640 * 479, kMapped, kGREY, 640, 480), FrameCheck::kShortPayload);
  // A compressed frame has no fixed size: a small JPEG is whole.
  EXPECT_EQ(check_frame(0, 1000, kMapped, kMJPG, 0, 480), FrameCheck::kUsable);
}

TEST(V4l2FrameCheck, EmptyBufferIsSkipped) {
  EXPECT_EQ(check_frame(0, 0, kMapped, kMJPG, 0, 480), FrameCheck::kEmpty);
  EXPECT_EQ(check_frame(0, 0, kMapped, kYUYV, 1280, 480), FrameCheck::kEmpty);
}

TEST(V4l2FrameCheck, ABufferClaimingMoreThanItsMappedLengthIsSkipped) {
  EXPECT_EQ(check_frame(0, 614401, 614400, kYUYV, 1280, 480), FrameCheck::kOverlong);
  EXPECT_EQ(check_frame(0, 614400, 614400, kYUYV, 1280, 480), FrameCheck::kUsable);
  EXPECT_EQ(check_frame(0, 50001, 50000, kMJPG, 0, 480), FrameCheck::kOverlong);
}

TEST(V4l2FrameCheck, EveryReasonHasAName) {
  std::set<std::string> names;
  for (FrameCheck c : {FrameCheck::kUsable, FrameCheck::kErrorFlag, FrameCheck::kShortPayload, FrameCheck::kEmpty,
                       FrameCheck::kOverlong, FrameCheck::kJpegNoStartMarker, FrameCheck::kJpegBadHeader,
                       FrameCheck::kJpegCutShort, FrameCheck::kJpegDamagedData, FrameCheck::kJpegWrongSize}) {
    EXPECT_STRNE(frame_check_name(c), "?");
    names.insert(frame_check_name(c));
  }
  EXPECT_EQ(names.size(), 10u) << "each reason its own words";
  EXPECT_STREQ(frame_check_name(FrameCheck::kShortPayload), "shorter than stride x height");
}

// MJPEG frames as a camera sends them (baseline, 4:2:2): camerad publishes whole ones and skips the
// rest, counting them in corrupt_frames, as it does truncated raw frames.
TEST(V4l2FrameCheck, AWholeMjpegFrameOfTheNegotiatedSizeIsUsable) {
  const std::vector<uint8_t> jpeg = whiskeye::test::mjpeg_pattern_jpeg(640, 480, 7);
  EXPECT_EQ(check_mjpeg(jpeg, 640, 480), FrameCheck::kUsable);
  EXPECT_EQ(check_mjpeg(jpeg, 1280, 720), FrameCheck::kJpegWrongSize);
}

TEST(V4l2FrameCheck, AnMjpegFrameCutShortOrWithGarbageAfterItsHeaderIsSkipped) {
  const std::vector<uint8_t> jpeg = whiskeye::test::mjpeg_pattern_jpeg(640, 480, 7);
  const std::vector<uint8_t> cut(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(jpeg.size() / 2));
  EXPECT_EQ(check_mjpeg(cut, 640, 480), FrameCheck::kJpegCutShort);
  // The header up to the first scan, then bytes that are no JPEG data, then an end marker.
  std::size_t pos = 2;
  while (jpeg[pos + 1] != 0xda) pos += 2 + ((jpeg[pos + 2] << 8) | jpeg[pos + 3]);
  std::vector<uint8_t> garbage(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(pos + 14));
  for (int i = 0; i < 20000; ++i) garbage.push_back(static_cast<uint8_t>(i * 7919 >> 3));
  garbage.insert(garbage.end(), {0xff, 0xd9});
  EXPECT_EQ(check_mjpeg(garbage, 640, 480), FrameCheck::kJpegDamagedData);
  EXPECT_EQ(check_mjpeg(std::vector<uint8_t>(614400, 0x80), 640, 480), FrameCheck::kJpegNoStartMarker);
}

// A frame hiding a 32000 x 32000 progressive header behind a stuffed FF 00 and an APP1 holding a
// 640x480 one (tests/support/hostile_jpeg.h): camerad never publishes a frame whose size slamd's
// decoder (libjpeg) would read otherwise than camerad did.
TEST(V4l2FrameCheck, AnMjpegFrameHidingAnotherFrameHeaderIsSkippedAsABrokenHeader) {
  EXPECT_EQ(check_mjpeg(whiskeye::test::camera_frame_hiding_progressive(640, 480, 32000, 32000), 640, 480),
            FrameCheck::kJpegBadHeader);
}

// The first buffer v4l2loopback 0.12.7 hands a reader that joined its writer with 12 frames written
// (vm.camerad_mjpeg, seen in a guest): VIDIOC_REQBUFS re-initialised it (sequence 0, bytesused the
// format's sizeimage, stamped then), so it holds frame 11 followed by the rest of the longer frame 3
// the ring held there before, and zeros. Its bytes read as damage; it is no frame of the session.
TEST(V4l2Session, TheBufferV4l2loopbackReinitialisedAtTheReadersRequestIsNoFrameOfTheSession) {
  const std::vector<uint8_t> older = whiskeye::test::mjpeg_pattern_jpeg(640, 480, 3);
  const std::vector<uint8_t> newest = whiskeye::test::mjpeg_pattern_jpeg(640, 480, 11);
  ASSERT_GT(older.size(), newest.size());
  std::vector<uint8_t> buffer(1228800, 0);  // sizeimage of 640x480 MJPG in v4l2loopback
  std::copy(older.begin(), older.end(), buffer.begin());
  std::copy(newest.begin(), newest.end(), buffer.begin());
  EXPECT_EQ(check_frame(0, buffer.size(), buffer.size(), kMJPG, 0, 480), FrameCheck::kUsable);
  EXPECT_EQ(check_mjpeg(buffer, 640, 480), FrameCheck::kJpegDamagedData) << "what camerad counted as damage";

  const int64_t requested_us = 11'749'984;  // CLOCK_MONOTONIC when VIDIOC_REQBUFS returned
  EXPECT_TRUE(from_before_session(0, requested_us - 171, requested_us, 0, 8));
  EXPECT_TRUE(from_before_session(0, requested_us, requested_us, 0, 8)) << "stamped within the same microsecond";
  // The writer had written only two frames: both positions the reader takes first were re-initialised.
  EXPECT_TRUE(from_before_session(0, requested_us - 171, requested_us, 1, 8));
}

TEST(V4l2Session, AFrameFilledAfterTheSessionAskedForItsBuffersIsOne) {
  const int64_t requested_us = 11'749'984;
  // A vb2 driver (UVC, vivid) numbers from 0 at STREAMON and stamps a buffer when it fills it.
  EXPECT_FALSE(from_before_session(0, requested_us + 40'000, requested_us, 0, 8));
  // v4l2loopback's next frames carry the writer's position and the time of the write.
  EXPECT_FALSE(from_before_session(19, requested_us + 62'756, requested_us, 1, 8));
  // A driver that leaves the timestamp 0, or stamps from the epoch, never.
  EXPECT_FALSE(from_before_session(0, 0, requested_us, 0, 8));
  EXPECT_FALSE(from_before_session(0, 1'700'000'000'000'000, requested_us, 0, 8));
  // A driver stamping with a clock of its own loses at most its first ring of frames numbered 0.
  EXPECT_TRUE(from_before_session(0, 5'000, requested_us, 7, 8));
  EXPECT_FALSE(from_before_session(0, 5'000, requested_us, 8, 8));
  EXPECT_FALSE(from_before_session(1, 5'000, requested_us, 0, 8));
}

TEST(V4l2Requeue, BufferWhoseQbufFailsIsKeptAndRetried) {
  std::vector<uint32_t> pending{2, 0};
  std::vector<uint32_t> queued;
  bool fail_buffer_2 = true;
  auto qbuf = [&](uint32_t index) {
    if (index == 2 && fail_buffer_2) return false;
    queued.push_back(index);
    return true;
  };
  EXPECT_EQ(requeue_all(pending, qbuf), 1);
  EXPECT_EQ(pending, std::vector<uint32_t>{2});
  EXPECT_EQ(queued, std::vector<uint32_t>{0});
  fail_buffer_2 = false;  // transient (e.g. EAGAIN, ENOMEM): the next call gives it back
  EXPECT_EQ(requeue_all(pending, qbuf), 0);
  EXPECT_TRUE(pending.empty());
  EXPECT_EQ(queued, (std::vector<uint32_t>{0, 2}));
}

TEST(V4l2Format, WhatTheDriverSettledOnIsCheckedBeforeStreaming) {
  const std::vector<uint32_t> wanted{kYUYV, kGREY};
  NegotiatedFormat yuyv{kYUYV, 640, 480, 1280, 614400, kFieldNone};
  EXPECT_EQ(format_problem(yuyv, wanted), "");
  NegotiatedFormat padded = yuyv;  // lines padded to 1344 bytes: fine, camerad publishes the stride
  padded.bytesperline = 1344;
  padded.sizeimage = 1344 * 480;
  EXPECT_EQ(format_problem(padded, wanted), "");

  NegotiatedFormat other = yuyv;
  other.pixelformat = kMJPG;
  EXPECT_EQ(format_problem(other, wanted), "the driver chose pixel format MJPG, which was not asked for");
  // Both fields interleaved (a TV input, as vivid's): a whole frame, line by line.
  for (uint32_t field : {4u, 8u, 9u}) {  // V4L2_FIELD_INTERLACED, _TB, _BT
    NegotiatedFormat interlaced = yuyv;
    interlaced.field = field;
    EXPECT_EQ(format_problem(interlaced, wanted), "") << field;
  }
  // One field per buffer (top, bottom, alternate), or the fields one after the other (seq_tb/bt).
  for (uint32_t field : {2u, 3u, 5u, 6u, 7u}) {
    NegotiatedFormat halves = yuyv;
    halves.field = field;
    EXPECT_EQ(format_problem(halves, wanted), "the driver chose v4l2_field " + std::to_string(field) +
                                                  ", which does not put a whole frame in a buffer line by line");
  }
  NegotiatedFormat no_stride = yuyv;
  no_stride.bytesperline = 0;
  EXPECT_EQ(format_problem(no_stride, wanted), "the driver's YUYV line of 0 bytes is shorter than 640 pixels x 2 bytes");
  NegotiatedFormat grey_short{kGREY, 640, 480, 639, 640 * 480, kFieldNone};
  EXPECT_NE(format_problem(grey_short, wanted).find("639 bytes is shorter than 640 pixels x 1 bytes"), std::string::npos);
  NegotiatedFormat small_image = yuyv;
  small_image.sizeimage = 1280 * 479;
  EXPECT_EQ(format_problem(small_image, wanted),
            "the driver's image size 613120 is smaller than 480 lines of 1280 bytes");
  NegotiatedFormat empty = yuyv;
  empty.height = 0;
  EXPECT_EQ(format_problem(empty, wanted), "the driver chose an empty image (640x0)");
  // A compressed format has no line length to check.
  NegotiatedFormat mjpg{kMJPG, 640, 480, 0, 0, kFieldNone};
  EXPECT_EQ(format_problem(mjpg, {kMJPG}), "");
}

TEST(V4l2Health, AnOpenCameraIsHealthyOnlyWhileFramesArrive) {
  constexpr int64_t kGap = 1000000;
  EXPECT_EQ(stream_problem(true, 200000, kGap, 0), "");
  EXPECT_EQ(stream_problem(true, 1000000, kGap, 0), "");
  // Open but no frame yet is not OK, however short the wait: a camera that opens and sends nothing
  // (USB bandwidth) must not look healthy after every reopen.
  EXPECT_EQ(stream_problem(false, 300000, kGap, 0), "open for 0.3 s, no frame yet");
  EXPECT_EQ(stream_problem(true, 2500000, kGap, 0), "no frame for 2.5 s");
  EXPECT_EQ(stream_problem(false, 1500000, kGap, 0), "open for 1.5 s, no frame yet");
  EXPECT_EQ(stream_problem(false, 1500000, kGap, 7), "open for 1.5 s, only damaged frames (7)");
}
