// Encoded LCM messages: encoding and decoding a whole message, and what is read or checked in a
// message's bytes without decoding it — a camera frame's header with its pixels as a view, a whisk
// cycle's counts before the generated decoder allocates for them, a message's sequence number. The
// byte offsets of lcmtypes/*.lcm are written here only; tests/common/test_message_layout.cpp checks
// each against the generated encoders. The contract checks of docs/lcm-channels.md that slamd and
// whiskeye-viewer both apply (a camera frame's size and format, a whisk cycle's counts, a sample time)
// are here too, so a message is refused in the same words wherever it is read.
#pragma once

#include <whiskeye/image_t.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace whiskeye {

// "cannot decode N bytes as whiskeye.<type><why>": the words of every refusal to decode.
std::string cannot_decode(std::size_t bytes, const char* type_name, const std::string& why);

// Encodes an LCM message. The caller keeps every array as long as its length field says: LCM's
// generated encoders index arrays by those fields without checking.
template <typename T>
std::vector<uint8_t> encode_message(const T& msg) {
  const int size = msg.getEncodedSize();
  std::vector<uint8_t> buf(static_cast<std::size_t>(size));
  if (size < 0 || msg.encode(buf.data(), 0, size) != size) {
    throw std::runtime_error(std::string("cannot encode ") + T::getTypeName());
  }
  return buf;
}

// Decodes an LCM message; false with a reason on a fingerprint mismatch, truncation, trailing bytes
// or a negative array count (the generated decoders size arrays from the message's counts before
// checking them against its length, and throw on a negative one; a huge count is the caller's to
// rule out first, see whisk_cycle_size_error).
template <typename T>
bool decode_message(std::span<const uint8_t> data, T& out, std::string* reason = nullptr) {
  int n = -1;
  std::string why = " (wrong type fingerprint or truncated)";
  try {
    n = out.decode(data.data(), 0, static_cast<int>(data.size()));
  } catch (const std::exception& e) {
    why = std::string(" (") + e.what() + ": an array count is negative or too large)";
  }
  if (n < 0 || static_cast<std::size_t>(n) != data.size()) {
    if (reason) *reason = cannot_decode(data.size(), T::getTypeName(), n < 0 ? why : " (trailing bytes)");
    return false;
  }
  return true;
}

// "" for a sample time that can be one (after 1970, before 2100), else why not, naming `channel`:
// one corrupt time (INT64_MAX, a negative one) would otherwise become data time and hold every later
// message back.
std::string sample_time_error(const char* channel, int64_t utime);

// --- CAMERA (image_t) ---

// The bytes of an encoded image_t before its pixels: fingerprint, utime, seq (8 each), width,
// height, row_stride, pixelformat, size (4 each). All a frame's checks read.
inline constexpr std::size_t kCameraFrameHeaderBytes = 44;

// A camera frame: image_t's fields, with the pixels as a view kept valid by `owner` (a replayed
// log's mapping, or one copy of a live message), so buffering and handing out frames never copies
// pixels.
struct CameraFrame {
  int64_t utime = 0;
  int64_t seq = 0;  // the driver's frame number
  int32_t width = 0;
  int32_t height = 0;
  int32_t row_stride = 0;
  int32_t pixelformat = 0;
  std::span<const uint8_t> data;  // image_t::data (its `size` bytes)
  std::shared_ptr<const void> owner;
};

// Decodes an encoded image_t without copying the pixels: out.data views `bytes` (out.owner is left
// alone). False with a reason, as decode_message() would give, on a fingerprint mismatch,
// truncation, a negative size or trailing bytes.
bool decode_camera_frame(std::span<const uint8_t> bytes, CameraFrame& out, std::string* reason = nullptr);
// Makes `frame` own a copy of the pixels it views (for bytes that do not outlive the caller).
void own_pixels(CameraFrame& frame);
// A frame owning a copy of `image`'s pixels.
CameraFrame camera_frame(const image_t& image);

// Why a frame breaks the contract (a sample time that is no epoch time, a size out of range, a
// pixel format outside docs/lcm-channels.md, pixels that do not fit width, height and row_stride),
// or "". slamd rejects such a frame; whiskeye-viewer does not show it.
std::string camera_frame_error(const CameraFrame& m);

// --- WHISK_CYCLE (whisk_cycle_t) ---

// Samples a whisk cycle may hold: 40 s at 500 Hz, far beyond any whisk cycle.
inline constexpr int kMaxSamplesPerCycle = 20000;

// Why the bytes of a whisk_cycle_t cannot be decoded safely (counts negative, or not matching the
// message's length), or "" when they can.
std::string whisk_cycle_size_error(std::span<const uint8_t> data);

// Why the counts of a whisk_cycle_t (whose size whisk_cycle_size_error() accepted) break the
// contract, or "". Checked before the generated decoder runs: it allocates a vector per sample, so a
// message of 0 whiskers and 20 M samples (200 MB) would take 2.3 GB before it was refused. Within
// the contract the decoded message is about 1.3× its wire size.
std::string whisk_cycle_contract_error(std::span<const uint8_t> data);

// The contract on a whisk cycle's counts (num_whiskers kNumWhiskers, num_samples
// 1..kMaxSamplesPerCycle), or "": the same words for the bytes and for a decoded message.
std::string whisk_cycle_counts_error(int32_t num_whiskers, int32_t num_samples);

// --- Any message with a sequence number ---

// The sequence number of an encoded message whose type carries one (told by its fingerprint, so a
// renamed channel is still read): image_t.seq (CAMERA), odometry_t.seq (ODOMETRY),
// whisker_sample_t.seq (WHISKER_SAMPLE), whisk_cycle_t.cycle (WHISK_CYCLE). nullopt otherwise.
std::optional<int64_t> sequence_number(std::span<const uint8_t> encoded);

}  // namespace whiskeye
