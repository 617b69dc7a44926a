// Known MJPEG test frames: a grey pattern that changes with a frame number and carries that number
// in its pixels, encoded as a camera would send it (baseline JPEG, YCbCr 4:2:2), and what a decoded
// frame must look like. Used by the VM test of camerad's MJPEG path (tests/vm: the writer feeding
// v4l2loopback and the checker decoding what camerad published), camerad's unit tests and the MJPEG
// decode benchmark. The frame number is 16 blocks of 16 x 16 pixels along the top (black 0, white
// 1), big enough to survive any JPEG quality; below them gradients and moving bars.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace whiskeye::test {

// The pattern of frame `number` (0 ... 65535): width x height grey values, row after row.
std::vector<uint8_t> mjpeg_pattern(int width, int height, uint32_t number);
// The pattern encoded as JPEG (R = G = B, YCbCr 4:2:2, `quality` 1-100). Throws std::runtime_error.
std::vector<uint8_t> mjpeg_pattern_jpeg(int width, int height, uint32_t number, int quality = 85);
// Any grey image (width x height, `stride` bytes a row) encoded the same way.
std::vector<uint8_t> encode_jpeg(std::span<const uint8_t> grey, int width, int height, int stride, int quality);

// The frame number a decoded pattern carries (-1 when a block is neither clearly black nor white).
int mjpeg_pattern_number(std::span<const uint8_t> grey, int width, int height, int stride);
// How far a decoded frame is from the pattern it carries: the mean and the largest absolute difference
// per pixel. A clean JPEG of quality 85 is within a mean of ~1 and a largest difference of ~40 (edges).
struct PatternDistance {
  double mean = 0;
  int max = 0;
};
PatternDistance mjpeg_pattern_distance(std::span<const uint8_t> grey, int width, int height, int stride,
                                       uint32_t number);

}  // namespace whiskeye::test
