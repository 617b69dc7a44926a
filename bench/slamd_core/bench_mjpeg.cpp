// mjpeg-bench: what one MJPEG camera frame costs slamd to decode to grey (the visual template's
// input), at 640x480 and 1280x720, against OpenCV's cv::imdecode and libturbojpeg's tjDecompress2 on
// the same frames, with a plain reference in the same run: slamd's conversion of a YUYV frame of the
// same size to grey (cv::cvtColor), i.e. what the frame would cost uncompressed. Figures in
// docs/performance.md ("### MJPEG decode").
// Frames: a camera-like grey image (gradients, edges, ±12 grey levels of sensor noise) encoded as a
// UVC camera sends it (baseline JPEG, YCbCr 4:2:2, quality 85; tests/support/mjpeg_pattern.h).
// Then the bounds on a hostile frame (tests/support/hostile_jpeg.h): what slamd's decoder costs to
// refuse the probes of docs/reliability.md ("Hostile input, round 3"), and to decode the costliest
// frame it takes, at the largest size it takes (4096 x 4096).
#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <turbojpeg.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "whiskeye/slamd/mjpeg_decode.h"
#include "hostile_jpeg.h"
#include "mjpeg_pattern.h"

namespace {

struct Size {
  int width, height;
};
constexpr Size kSizes[] = {{640, 480}, {1280, 720}};

const std::vector<uint8_t>& frame(int which) {
  static std::vector<uint8_t> frames[2];
  std::vector<uint8_t>& f = frames[which];
  if (f.empty()) {
    const auto [w, h] = kSizes[which];
    std::vector<uint8_t> grey = whiskeye::test::mjpeg_pattern(w, h, 77);
    std::mt19937 rng(1);
    std::uniform_int_distribution<int> noise(-12, 12);
    for (uint8_t& p : grey) p = static_cast<uint8_t>(std::clamp(p + noise(rng), 0, 255));
    f = whiskeye::test::encode_jpeg(grey, w, h, w, 85);
  }
  return f;
}

void label(benchmark::State& state) {
  const auto [w, h] = kSizes[state.range(0)];
  state.SetLabel(std::to_string(w) + "x" + std::to_string(h) + ", " + std::to_string(frame(state.range(0)).size() / 1024) +
                 " KiB");
}

void BM_MjpegDecodeSlamd(benchmark::State& state) {
  const auto [w, h] = kSizes[state.range(0)];
  const std::vector<uint8_t>& jpeg = frame(state.range(0));
  std::vector<uint8_t> grey(static_cast<std::size_t>(w) * h);
  for (auto _ : state) {
    whiskeye::slamd::decode_mjpeg_grey(jpeg, w, h, grey.data(), static_cast<std::size_t>(w));
    benchmark::DoNotOptimize(grey.data());
  }
  label(state);
}

// What the SLAM core and the viewer pay before they allocate the image: check_mjpeg_frame(), which
// has libjpeg read the header (the decode reads it again).
void BM_MjpegCheckSlamd(benchmark::State& state) {
  const auto [w, h] = kSizes[state.range(0)];
  const std::vector<uint8_t>& jpeg = frame(state.range(0));
  for (auto _ : state) whiskeye::slamd::check_mjpeg_frame(jpeg, w, h);
  label(state);
}

void BM_MjpegDecodeImdecode(benchmark::State& state) {
  const std::vector<uint8_t>& jpeg = frame(state.range(0));
  const cv::Mat buf(1, static_cast<int>(jpeg.size()), CV_8UC1, const_cast<uint8_t*>(jpeg.data()));
  for (auto _ : state) {
    cv::Mat grey = cv::imdecode(buf, cv::IMREAD_GRAYSCALE);
    benchmark::DoNotOptimize(grey.data);
  }
  label(state);
}

void BM_MjpegDecodeTurbojpeg(benchmark::State& state) {
  const auto [w, h] = kSizes[state.range(0)];
  const std::vector<uint8_t>& jpeg = frame(state.range(0));
  std::vector<uint8_t> grey(static_cast<std::size_t>(w) * h);
  tjhandle tj = tjInitDecompress();
  for (auto _ : state) {
    if (tjDecompress2(tj, jpeg.data(), jpeg.size(), grey.data(), w, w, h, TJPF_GRAY, TJFLAG_STOPONWARNING) != 0) {
      state.SkipWithError(tjGetErrorStr2(tj));
      break;
    }
    benchmark::DoNotOptimize(grey.data());
  }
  tjDestroy(tj);
  label(state);
}

// The plain reference: a YUYV frame of the same size to grey, as slamd converts uncompressed frames.
void BM_YuyvToGreyReference(benchmark::State& state) {
  const auto [w, h] = kSizes[state.range(0)];
  const cv::Mat yuyv(h, w, CV_8UC2, cv::Scalar(90, 128));
  cv::Mat grey;
  for (auto _ : state) {
    cv::cvtColor(yuyv, grey, cv::COLOR_YUV2GRAY_YUYV);
    benchmark::DoNotOptimize(grey.data);
  }
  label(state);
}

// The probes, each refused by slamd's decoder (the time is the refusal's): 0 a 640x480 frame hiding a
// 32000 x 32000 progressive header (905 bytes; 2.0 GB and 5 s before), 1 a progressive 4096 x 4096
// frame of 15,000 repeated AC scans (561 kB; 18-30 s before), 2 the same at 640x480 with 40,000.
struct Probe {
  const char* name;
  int width, height;
  std::vector<uint8_t> (*make)();
};
const Probe kProbes[] = {
    {"hidden 32000x32000 header", 640, 480,
     [] { return whiskeye::test::camera_frame_hiding_progressive(640, 480, 32000, 32000); }},
    {"4096x4096, 15,000 AC scans", 4096, 4096, [] { return whiskeye::test::progressive_with_repeated_scans(4096, 4096, 15'000); }},
    {"640x480, 40,000 AC scans", 640, 480, [] { return whiskeye::test::progressive_with_repeated_scans(640, 480, 40'000); }},
};

void BM_MjpegRefuseHostile(benchmark::State& state) {
  const Probe& p = kProbes[state.range(0)];
  const std::vector<uint8_t> jpeg = p.make();
  std::vector<uint8_t> grey(static_cast<std::size_t>(p.width) * p.height);
  for (auto _ : state) {
    try {
      whiskeye::slamd::decode_mjpeg_grey(jpeg, p.width, p.height, grey.data(), static_cast<std::size_t>(p.width));
      state.SkipWithError("the probe was decoded");
      break;
    } catch (const whiskeye::slam::InputError&) {
    }
  }
  state.SetLabel(std::string(p.name) + ", " + std::to_string(jpeg.size()) + " bytes");
}

// The upper bound on one frame: the costliest baseline frame per pixel the decoder takes
// (costliest_baseline_jpeg: RGB noise, 4:4:4, quality 100, a restart marker every MCU) at 4096 x 4096.
void BM_MjpegDecodeCostliestAccepted(benchmark::State& state) {
  constexpr int kSide = 4096;
  const std::vector<uint8_t> jpeg = whiskeye::test::costliest_baseline_jpeg(kSide, kSide, 1);
  std::vector<uint8_t> grey(static_cast<std::size_t>(kSide) * kSide);
  for (auto _ : state) {
    whiskeye::slamd::decode_mjpeg_grey(jpeg, kSide, kSide, grey.data(), kSide);
    benchmark::DoNotOptimize(grey.data());
  }
  state.SetLabel("4096x4096, " + std::to_string(jpeg.size() / (1024 * 1024)) + " MiB");
}

}  // namespace

BENCHMARK(BM_MjpegDecodeSlamd)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MjpegCheckSlamd)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MjpegDecodeImdecode)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MjpegDecodeTurbojpeg)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_YuyvToGreyReference)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MjpegRefuseHostile)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_MjpegDecodeCostliestAccepted)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
