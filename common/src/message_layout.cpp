// The layout of encoded messages (message_layout.h).
#include "whiskeye/common/message_layout.h"

#include "whiskeye/common/big_endian.h"
#include "whiskeye/common/whisker_array.h"

#include <whiskeye/odometry_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

namespace whiskeye {
namespace {

// Every message starts with its type's 8-byte fingerprint.
constexpr std::size_t kFingerprintBytes = 8;

constexpr std::size_t kImageHeaderBytes = kCameraFrameHeaderBytes;
static_assert(kImageHeaderBytes == kFingerprintBytes + 8 + 8 + 5 * 4);

// whisk_cycle_t: fingerprint, then utime, cycle, utime_start, utime_end (8 each); then num_whiskers,
// num_samples, num_missing (4 each); then per sample utime (8), valid (1), phase (1), and per sample
// and whisker three floats and a byte.
constexpr std::size_t kWhiskCycleCountsAt = kFingerprintBytes + 4 * 8;
constexpr std::size_t kWhiskCycleFixedBytes = kWhiskCycleCountsAt + 3 * 4;
constexpr int64_t kWhiskCycleBytesPerSample = 8 + 1 + 1;
constexpr int64_t kWhiskCycleBytesPerWhiskerSample = 3 * 4 + 1;

// image_t, odometry_t, whisker_sample_t and whisk_cycle_t start with `int64_t utime` and then their
// sequence number.
constexpr std::size_t kSequenceNumberAt = kFingerprintBytes + 8;

// Bytes per pixel of the uncompressed formats docs/lcm-channels.md allows; 0 for compressed, -1 for
// any other.
int bytes_per_pixel(int32_t fourcc) {
  if (fourcc == image_t::PIXEL_FORMAT_GREY) return 1;
  if (fourcc == image_t::PIXEL_FORMAT_YUYV) return 2;
  if (fourcc == image_t::PIXEL_FORMAT_RGB24 || fourcc == image_t::PIXEL_FORMAT_BGR24) return 3;
  if (fourcc == image_t::PIXEL_FORMAT_MJPEG) return 0;
  return -1;
}

}  // namespace

std::string cannot_decode(std::size_t bytes, const char* type_name, const std::string& why) {
  return "cannot decode " + std::to_string(bytes) + " bytes as whiskeye." + type_name + why;
}

std::string sample_time_error(const char* channel, int64_t utime) {
  constexpr int64_t kYear2100 = 4'102'444'800'000'000;
  if (utime > 0 && utime < kYear2100) return "";
  return std::string(channel) + ": sample time " + std::to_string(utime) + " us is not a plausible epoch time";
}

bool decode_camera_frame(std::span<const uint8_t> bytes, CameraFrame& out, std::string* reason) {
  const auto fail = [&](const char* why) {
    if (reason) *reason = cannot_decode(bytes.size(), image_t::getTypeName(), why);
    return false;
  };
  if (bytes.size() < kImageHeaderBytes || read_be_i64(bytes.data()) != image_t::getHash()) {
    return fail(" (wrong type fingerprint or truncated)");
  }
  const uint8_t* p = bytes.data() + kFingerprintBytes;
  const auto size = read_be_i32(p + 32);
  if (size < 0 || bytes.size() - kImageHeaderBytes < static_cast<std::size_t>(size)) {
    return fail(" (wrong type fingerprint or truncated)");
  }
  if (bytes.size() - kImageHeaderBytes != static_cast<std::size_t>(size)) return fail(" (trailing bytes)");
  out.utime = read_be_i64(p);
  out.seq = read_be_i64(p + 8);
  out.width = read_be_i32(p + 16);
  out.height = read_be_i32(p + 20);
  out.row_stride = read_be_i32(p + 24);
  out.pixelformat = read_be_i32(p + 28);
  out.data = bytes.subspan(kImageHeaderBytes);
  return true;
}

void own_pixels(CameraFrame& frame) {
  auto copy = std::make_shared<const std::vector<uint8_t>>(frame.data.begin(), frame.data.end());
  frame.data = std::span<const uint8_t>(copy->data(), copy->size());
  frame.owner = std::move(copy);
}

CameraFrame camera_frame(const image_t& image) {
  CameraFrame f{image.utime, image.seq, image.width, image.height, image.row_stride, image.pixelformat,
                std::span<const uint8_t>(image.data.data(), image.data.size()), nullptr};
  own_pixels(f);
  return f;
}

std::string camera_frame_error(const CameraFrame& m) {
  if (std::string bad = sample_time_error("CAMERA", m.utime); !bad.empty()) return bad;
  if (m.width <= 0 || m.height <= 0 || m.width > 10000 || m.height > 10000) {
    return "CAMERA: bad size " + std::to_string(m.width) + "x" + std::to_string(m.height);
  }
  const int bpp = bytes_per_pixel(m.pixelformat);
  if (bpp < 0) return "CAMERA: unsupported pixel format " + std::to_string(m.pixelformat);
  if (bpp == 0) return !m.data.empty() ? "" : "CAMERA: empty compressed frame";
  if (m.row_stride < m.width * bpp) return "CAMERA: row_stride " + std::to_string(m.row_stride) + " < width × bytes per pixel";
  if (static_cast<int64_t>(m.data.size()) < static_cast<int64_t>(m.row_stride) * m.height) {
    return "CAMERA: " + std::to_string(m.data.size()) + " bytes < row_stride × height";
  }
  return "";
}

std::string whisk_cycle_size_error(std::span<const uint8_t> data) {
  const std::string what = cannot_decode(data.size(), whisk_cycle_t::getTypeName(), ": ");
  if (data.size() < kWhiskCycleFixedBytes) return what + "shorter than its fixed fields";
  const int64_t whiskers = read_be_i32(data.data() + kWhiskCycleCountsAt);
  const int64_t samples = read_be_i32(data.data() + kWhiskCycleCountsAt + 4);
  if (whiskers < 0 || samples < 0) {
    return what + "negative num_whiskers (" + std::to_string(whiskers) + ") or num_samples (" +
           std::to_string(samples) + ")";
  }
  // Compared by division: samples · whiskers · 13 overflows int64 for counts near INT32_MAX.
  const int64_t per_sample = kWhiskCycleBytesPerSample + kWhiskCycleBytesPerWhiskerSample * whiskers;
  const int64_t rest = static_cast<int64_t>(data.size() - kWhiskCycleFixedBytes);
  if (rest % per_sample != 0 || rest / per_sample != samples) {
    return what + "num_samples " + std::to_string(samples) + " and num_whiskers " + std::to_string(whiskers) +
           " need " + std::to_string(per_sample) + " bytes per sample, the message has " + std::to_string(rest) +
           " after its fixed fields";
  }
  return {};
}

std::string whisk_cycle_counts_error(int32_t num_whiskers, int32_t num_samples) {
  if (num_whiskers != kNumWhiskers) {
    return "WHISK_CYCLE: num_whiskers " + std::to_string(num_whiskers) + " (expected " + std::to_string(kNumWhiskers) + ")";
  }
  if (num_samples <= 0 || num_samples > kMaxSamplesPerCycle) {
    return "WHISK_CYCLE: num_samples " + std::to_string(num_samples) + " out of range";
  }
  return "";
}

std::string whisk_cycle_contract_error(std::span<const uint8_t> data) {
  if (data.size() < kWhiskCycleCountsAt + 8) return "WHISK_CYCLE: shorter than its fixed fields";
  return whisk_cycle_counts_error(read_be_i32(data.data() + kWhiskCycleCountsAt),
                                  read_be_i32(data.data() + kWhiskCycleCountsAt + 4));
}

std::optional<int64_t> sequence_number(std::span<const uint8_t> encoded) {
  if (encoded.size() < kSequenceNumberAt + 8) return std::nullopt;
  const int64_t fingerprint = read_be_i64(encoded.data());
  for (const int64_t hash : {image_t::getHash(), odometry_t::getHash(), whisker_sample_t::getHash(),
                             whisk_cycle_t::getHash()}) {
    if (fingerprint == hash) return read_be_i64(encoded.data() + kSequenceNumberAt);
  }
  return std::nullopt;
}

}  // namespace whiskeye
