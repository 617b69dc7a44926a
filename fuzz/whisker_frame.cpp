// Fuzz target: the whisker CAN frame decoder (drivers/whisker_protocol), as whiskerd runs it on its
// real-time thread. Input: 2 bytes CAN id (11 bits), 1 byte flags (bit 0: arrived as a CAN FD frame,
// bit 1: classic bus mode), then the frame's data (at most 64 bytes, as on the bus).
// Checks beyond "no crash": a rejected frame has a reason that formats without allocating, and an FD
// sample that decodes re-encodes to the same bytes.
#include "whiskeye/whisker_protocol/whisker_protocol.h"

#include <cstdlib>
#include <cstring>

using namespace whiskeye::wp;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  const uint32_t id = ((uint32_t{data[0]} << 8) | data[1]) & 0x7FF;
  const bool fd = (data[2] & 1) != 0;
  const BusMode mode = (data[2] & 2) != 0 ? BusMode::kClassic : BusMode::kFd;
  const std::span<const uint8_t> frame(data + 3, std::min<size_t>(size - 3, 64));
  const Decoded d = decode_frame(id, fd, frame, mode);
  char text[kRejectTextBytes];
  format_reject(d, text);
  if (std::memchr(text, 0, sizeof text) == nullptr) std::abort();
  if (d.kind == FrameKind::kRejected) {
    if (reject_text(d).empty()) std::abort();  // every rejection says why
  } else if (d.kind == FrameKind::kSample && mode == BusMode::kFd) {
    uint8_t again[kFdSampleBytes];
    const size_t n = encode_sample_fd(d.sample, again);
    const Decoded back = decode_frame(id, fd, std::span<const uint8_t>(again, n), mode);
    if (back.kind != FrameKind::kSample || back.sample.seq != d.sample.seq || back.sample.status != d.sample.status) {
      std::abort();
    }
  }
  return 0;
}
