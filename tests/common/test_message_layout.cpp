// The layout of encoded messages (common/message_layout.h) against LCM's generated encoders: every
// byte offset it reads is checked here by encoding a message with the generated type and peeking.
#include "whiskeye/common/message_layout.h"

#include "whiskeye/common/whisker_array.h"

#include <whiskeye/image_t.hpp>
#include <whiskeye/odometry_t.hpp>
#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>

namespace whiskeye {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;

// A whisk cycle of `samples` samples of `whiskers` whiskers, consistent in every count.
whisk_cycle_t whisk_cycle(int32_t whiskers, int32_t samples) {
  whisk_cycle_t c{};
  c.utime = c.utime_end = kT0 + kMaxSamplesPerCycle;
  c.utime_start = kT0;
  c.cycle = 9;
  c.num_whiskers = whiskers;
  c.num_samples = samples;
  for (int32_t s = 0; s < samples; ++s) {
    c.sample_utime.push_back(kT0 + s);
    c.sample_valid.push_back(1);
    c.phase.push_back(0);
    c.theta.emplace_back(static_cast<std::size_t>(whiskers), 0.0f);
    c.deflection_x.emplace_back(static_cast<std::size_t>(whiskers), 0.0f);
    c.deflection_y.emplace_back(static_cast<std::size_t>(whiskers), 0.0f);
    c.contact.emplace_back(static_cast<std::size_t>(whiskers), int8_t{0});
  }
  return c;
}

void put_be32(std::vector<uint8_t>& b, std::size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

// Where num_samples is in an encoded whisk_cycle_t: where the encodings of one and of two samples
// first differ is its last byte.
std::size_t num_samples_offset() {
  const std::vector<uint8_t> one = encode_message(whisk_cycle(kNumWhiskers, 1));
  const std::vector<uint8_t> two = encode_message(whisk_cycle(kNumWhiskers, 2));
  return static_cast<std::size_t>(std::mismatch(one.begin(), one.end(), two.begin()).first - one.begin()) - 3;
}

// A frame of `width` x `height` pixels of `format`, `row_stride` bytes a row, holding `bytes` bytes.
image_t image(int32_t width, int32_t height, int32_t row_stride, int32_t format, int32_t bytes) {
  image_t im{};
  im.utime = kT0;
  im.seq = 7;
  im.width = width;
  im.height = height;
  im.row_stride = row_stride;
  im.pixelformat = format;
  im.size = bytes;
  for (int32_t i = 0; i < bytes; ++i) im.data.push_back(static_cast<uint8_t>(200 + i));
  return im;
}

TEST(MessageLayout, ACameraFrameDecodesAsLcmDoesWithoutCopyingThePixels) {
  const image_t im = image(3, 2, 6, image_t::PIXEL_FORMAT_YUYV, 12);
  const std::vector<uint8_t> bytes = encode_message(im);
  CameraFrame f;
  ASSERT_TRUE(decode_camera_frame(bytes, f));
  EXPECT_EQ(f.utime, kT0);
  EXPECT_EQ(f.seq, 7);
  EXPECT_EQ(f.width, 3);
  EXPECT_EQ(f.height, 2);
  EXPECT_EQ(f.row_stride, 6);
  EXPECT_EQ(f.pixelformat, image_t::PIXEL_FORMAT_YUYV);
  EXPECT_EQ(std::vector<uint8_t>(f.data.begin(), f.data.end()), im.data);
  EXPECT_EQ(f.data.data(), bytes.data() + bytes.size() - 12) << "a view into the message";
  own_pixels(f);
  EXPECT_NE(f.data.data(), bytes.data() + bytes.size() - 12) << "a copy it owns";
  EXPECT_EQ(std::vector<uint8_t>(f.data.begin(), f.data.end()), im.data);
  EXPECT_NE(f.owner, nullptr);
}

TEST(MessageLayout, ACameraFrameIsRefusedWhereLcmRefusesIt) {
  const std::vector<uint8_t> good = encode_message(image(2, 2, 2, image_t::PIXEL_FORMAT_GREY, 4));
  auto both_reject = [](const std::vector<uint8_t>& bytes, const char* why) {
    CameraFrame f;
    std::string reason;
    std::string lcm_reason;
    image_t lcm_decoded;
    EXPECT_FALSE(decode_message(bytes, lcm_decoded, &lcm_reason)) << why;
    EXPECT_FALSE(decode_camera_frame(bytes, f, &reason)) << why;
    EXPECT_NE(reason.find("whiskeye.image_t"), std::string::npos) << why;
    return reason;
  };
  std::vector<uint8_t> b = good;
  b.pop_back();
  EXPECT_NE(both_reject(b, "truncated pixels").find("truncated"), std::string::npos);
  b.resize(20);
  both_reject(b, "truncated header");
  b = good;
  b[0] ^= 1;
  EXPECT_NE(both_reject(b, "fingerprint").find("fingerprint"), std::string::npos);
  b = good;
  b.push_back(0);
  EXPECT_EQ(both_reject(b, "trailing"), "cannot decode " + std::to_string(b.size()) + " bytes as whiskeye.image_t (trailing bytes)");
  odometry_t other{};
  both_reject(encode_message(other), "another type");
  // A negative size: LCM's decoder would try to allocate it; ours refuses.
  b = good;
  b[40] = 0xff;
  CameraFrame f;
  EXPECT_FALSE(decode_camera_frame(b, f));
}

TEST(MessageLayout, ACameraFrameOutsideTheContractIsNamed) {
  const image_t im = image(4, 2, 4, image_t::PIXEL_FORMAT_GREY, 8);
  EXPECT_EQ(camera_frame_error(camera_frame(im)), "");
  image_t bad = im;
  bad.utime = -1;
  EXPECT_EQ(camera_frame_error(camera_frame(bad)), "CAMERA: sample time -1 us is not a plausible epoch time");
  bad = im;
  bad.width = 0;
  EXPECT_EQ(camera_frame_error(camera_frame(bad)), "CAMERA: bad size 0x2");
  bad = im;
  bad.pixelformat = 42;
  EXPECT_EQ(camera_frame_error(camera_frame(bad)), "CAMERA: unsupported pixel format 42");
  bad = im;
  bad.row_stride = 3;
  EXPECT_NE(camera_frame_error(camera_frame(bad)).find("row_stride 3"), std::string::npos);
  bad = im;
  bad.pixelformat = image_t::PIXEL_FORMAT_YUYV;  // 2 bytes a pixel: 8 bytes are half a frame
  bad.row_stride = 8;
  EXPECT_EQ(camera_frame_error(camera_frame(bad)), "CAMERA: 8 bytes < row_stride × height");
  bad = im;
  bad.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
  bad.size = 0;
  bad.data.clear();
  EXPECT_EQ(camera_frame_error(camera_frame(bad)), "CAMERA: empty compressed frame");
}

TEST(MessageLayout, AWhiskCyclesCountsAreReadWhereTheEncoderWritesThem) {
  const std::vector<uint8_t> good = encode_message(whisk_cycle(kNumWhiskers, 3));
  EXPECT_EQ(whisk_cycle_size_error(good), "");
  EXPECT_EQ(whisk_cycle_contract_error(good), "");
  // Three whiskers, one sample: sized right, outside the contract, named with the count it holds.
  const std::vector<uint8_t> three = encode_message(whisk_cycle(3, 1));
  EXPECT_EQ(whisk_cycle_size_error(three), "");
  EXPECT_EQ(whisk_cycle_contract_error(three), "WHISK_CYCLE: num_whiskers 3 (expected 24)");
  EXPECT_EQ(whisk_cycle_contract_error(encode_message(whisk_cycle(kNumWhiskers, kMaxSamplesPerCycle + 1))),
            "WHISK_CYCLE: num_samples 20001 out of range");
  EXPECT_EQ(whisk_cycle_counts_error(kNumWhiskers, 0), "WHISK_CYCLE: num_samples 0 out of range");
  // One sample more or less than the counts say: the length no longer fits.
  std::vector<uint8_t> shorter = good;
  shorter.resize(shorter.size() - 1);
  EXPECT_NE(whisk_cycle_size_error(shorter).find("num_samples 3 and num_whiskers 24 need 322 bytes per sample"),
            std::string::npos)
      << whisk_cycle_size_error(shorter);
  EXPECT_EQ(whisk_cycle_size_error(std::vector<uint8_t>(good.begin(), good.begin() + 30)),
            "cannot decode 30 bytes as whiskeye.whisk_cycle_t: shorter than its fixed fields");
}

TEST(MessageLayout, AWhiskCycleWhoseCountsDoNotFitItsLengthIsRefusedWithoutOverflow) {
  const std::vector<uint8_t> good = encode_message(whisk_cycle(kNumWhiskers, 1));
  const std::size_t at = num_samples_offset();
  auto with_samples = [&](uint32_t n) {
    std::vector<uint8_t> b = good;
    put_be32(b, at, n);
    return b;
  };
  EXPECT_NE(whisk_cycle_size_error(with_samples(0xffffffffu)).find("negative"), std::string::npos);
  EXPECT_NE(whisk_cycle_size_error(with_samples(0x7fffffffu)).find("num_samples 2147483647"), std::string::npos);
  // Counts whose product wraps: 52 + 10·s + 13·s·w is exactly 1024 modulo 2^64 for these, so a
  // size check by multiplication would let a 1024-byte message through to the decoder's allocation.
  std::vector<uint8_t> wraps(1024, 0);
  std::copy(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(at), wraps.begin());
  put_be32(wraps, at - 4, 1982474090u);  // num_whiskers
  put_be32(wraps, at, 2147287049u);      // num_samples
  const std::string wrap_error = whisk_cycle_size_error(wraps);
  EXPECT_NE(wrap_error.find("num_samples 2147287049"), std::string::npos) << wrap_error;
}

TEST(MessageLayout, ReadsTheSequenceNumberOfEveryTypeThatCarriesOne) {
  odometry_t odo{};
  odo.utime = 5;
  odo.seq = 42;
  whisker_sample_t ws{};
  ws.utime = 5;
  ws.seq = 43;
  EXPECT_EQ(sequence_number(encode_message(image(2, 2, 2, image_t::PIXEL_FORMAT_GREY, 4))), 7);
  EXPECT_EQ(sequence_number(encode_message(odo)), 42);
  EXPECT_EQ(sequence_number(encode_message(ws)), 43);
  EXPECT_EQ(sequence_number(encode_message(whisk_cycle(kNumWhiskers, 1))), 9);
  pose2d_t pose{};
  EXPECT_EQ(sequence_number(encode_message(pose)), std::nullopt) << "no sequence number";
  EXPECT_EQ(sequence_number(std::vector<uint8_t>(10, 0)), std::nullopt) << "too short";
}

TEST(MessageLayout, ASampleTimeIsAnEpochTimeBefore2100) {
  EXPECT_EQ(sample_time_error("ODOMETRY", kT0), "");
  EXPECT_EQ(sample_time_error("ODOMETRY", 0), "ODOMETRY: sample time 0 us is not a plausible epoch time");
  EXPECT_NE(sample_time_error("WHISK_CYCLE", INT64_MAX), "");
}

}  // namespace
}  // namespace whiskeye
