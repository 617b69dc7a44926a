// Known MJPEG test frames (see mjpeg_pattern.h), encoded with libturbojpeg.
#include "mjpeg_pattern.h"

#include <turbojpeg.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

namespace whiskeye::test {
namespace {

constexpr int kBits = 16, kBlock = 16;

uint8_t pattern_at(int x, int y, int width, int height, uint32_t number) {
  if (y < kBlock && x < kBits * kBlock) return ((number >> (x / kBlock)) & 1) ? 235 : 20;
  if (y < kBlock + 8) return 128;  // a grey gap under the number
  // Smooth gradients (most of a camera image) and diagonal bars moving 8 pixels a frame (edges).
  const int gradient = 40 + (x * 120) / width + (y * 60) / height;
  const bool bar = ((x + y + 8 * static_cast<int>(number)) / 24) % 4 == 0;
  return static_cast<uint8_t>(bar ? gradient + 50 : gradient);
}

}  // namespace

std::vector<uint8_t> mjpeg_pattern(int width, int height, uint32_t number) {
  std::vector<uint8_t> grey(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) grey[static_cast<std::size_t>(y) * width + x] = pattern_at(x, y, width, height, number);
  }
  return grey;
}

std::vector<uint8_t> encode_jpeg(std::span<const uint8_t> grey, int width, int height, int stride, int quality) {
  std::vector<uint8_t> rgb(static_cast<std::size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::fill_n(&rgb[(static_cast<std::size_t>(y) * width + x) * 3], 3, grey[static_cast<std::size_t>(y) * stride + x]);
    }
  }
  const std::unique_ptr<void, int (*)(tjhandle)> tj(tjInitCompress(), tjDestroy);
  if (!tj) throw std::runtime_error("tjInitCompress failed");
  unsigned char* out = nullptr;
  unsigned long size = 0;
  if (tjCompress2(tj.get(), rgb.data(), width, 0, height, TJPF_RGB, &out, &size, TJSAMP_422, quality, 0) != 0) {
    tjFree(out);
    throw std::runtime_error(std::string("tjCompress2: ") + tjGetErrorStr2(tj.get()));
  }
  std::vector<uint8_t> jpeg(out, out + size);
  tjFree(out);
  return jpeg;
}

std::vector<uint8_t> mjpeg_pattern_jpeg(int width, int height, uint32_t number, int quality) {
  return encode_jpeg(mjpeg_pattern(width, height, number), width, height, width, quality);
}

int mjpeg_pattern_number(std::span<const uint8_t> grey, int width, int height, int stride) {
  if (width < kBits * kBlock || height < kBlock) return -1;
  int number = 0;
  for (int bit = 0; bit < kBits; ++bit) {
    // The block's middle 8 x 8 pixels: away from the edges JPEG blurs.
    int sum = 0;
    for (int y = 4; y < 12; ++y) {
      for (int x = 4; x < 12; ++x) sum += grey[static_cast<std::size_t>(y) * stride + bit * kBlock + x];
    }
    const int mean = sum / 64;
    if (mean > 170) {
      number |= 1 << bit;
    } else if (mean >= 85) {
      return -1;
    }
  }
  return number;
}

PatternDistance mjpeg_pattern_distance(std::span<const uint8_t> grey, int width, int height, int stride,
                                       uint32_t number) {
  PatternDistance d;
  double sum = 0;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int diff = std::abs(grey[static_cast<std::size_t>(y) * stride + x] - pattern_at(x, y, width, height, number));
      sum += diff;
      d.max = std::max(d.max, diff);
    }
  }
  d.mean = sum / (static_cast<double>(width) * height);
  return d;
}

}  // namespace whiskeye::test
