// Fuzz target: slamd's MJPEG decoder as the SLAM core and the viewer call it on a CAMERA frame:
// check_mjpeg_frame() with the message's size, then, if it passes, a buffer of that size and
// decode_mjpeg_grey() into it. A refusal (InputError) is an answer; the check must be what bounds the
// decode: libjpeg allocating for a header the check did not see, or decoding for longer than one
// pass over a frame of at most 4096 x 4096 pixels, is a finding (scripts/fuzz gives this target a
// tighter malloc limit and timeout than the others).
// Input: [width, 2 bytes big-endian][height, 2 bytes big-endian][the JPEG's bytes].
// Seeds: fuzz/corpus/mjpeg_frame, a simulator frame and the probes of tests/support/hostile_jpeg.h
// (fuzz_make_seeds).
#include "whiskeye/slamd/mjpeg_decode.h"

#include <cstdlib>
#include <span>
#include <vector>

using namespace whiskeye;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  const int width = (data[0] << 8) | data[1];
  const int height = (data[2] << 8) | data[3];
  const std::span<const uint8_t> jpeg(data + 4, size - 4);
  try {
    slamd::check_mjpeg_frame(jpeg, width, height);
  } catch (const slam::InputError&) {
    return 0;
  }
  // Passed: the header is the message's size, so at most 4096 x 4096 pixels, and at least 1 x 1.
  if (width <= 0 || height <= 0 || int64_t{width} * height > int64_t{4096} * 4096) std::abort();
  std::vector<uint8_t> grey(static_cast<std::size_t>(width) * height);
  try {
    slamd::decode_mjpeg_grey(jpeg, width, height, grey.data(), static_cast<std::size_t>(width));
  } catch (const slam::InputError&) {
  }
  return 0;
}
