// VM test program of the MJPEG scenario (scenario_camerad_mjpeg.sh): records what camerad publishes on
// CAMERA while the writer feeds v4l2loopback known frames and damaged ones, until SIGTERM (or
// --seconds), then decodes every frame with slamd's decoder (slamd::decode_mjpeg_grey) and reports
// one PASS/FAIL line per behaviour: the frames are 640x480 MJPG as negotiated, every one decodes (no
// damaged frame got through camerad), each carries the pattern the writer drew for its number
// (within a JPEG's tolerance), and the numbers only go up (no frame twice, none out of order).
//   mjpeg_vm_check --results FILE [--seconds MAX] [--min-frames N]
#include <signal.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <fstream>
#include <iostream>
#include <vector>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/image_t.hpp>

#include "whiskeye/slamd/mjpeg_decode.h"
#include "mjpeg_pattern.h"

#include "vm_report.h"

using namespace whiskeye;

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"camerad MJPEG VM test: CAMERA decoded and compared with the written pattern"};
  double seconds = 300;
  int min_frames = 50;
  std::string results_path;
  app.add_option("--seconds", seconds);
  app.add_option("--min-frames", min_frames);
  app.add_option("--results", results_path)->required();
  CLI11_PARSE(app, argc, argv);
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);

  // Decoding waits for the end: on an emulated CPU it would take the time camerad needs.
  std::vector<image_t> frames;
  LcmBus bus;
  DecodeErrors errors;
  subscribe<image_t>(bus, "CAMERA", [&](const image_t& m) { frames.push_back(m); }, errors);
  const int64_t end = monotonic_us() + static_cast<int64_t>(seconds * 1e6);
  while (!g_stop.load() && monotonic_us() < end) bus.handle_timeout(100);

  vm::Report report(results_path);

  report("camerad_publishes_mjpeg_frames", static_cast<int>(frames.size()) >= min_frames,
         std::to_string(frames.size()) + " frames, " + std::to_string(min_frames) + " expected at least");
  std::string why;
  bool format_ok = !frames.empty();
  for (const image_t& f : frames) {
    if (f.width != 640 || f.height != 480 || f.pixelformat != image_t::PIXEL_FORMAT_MJPEG || f.row_stride != 0 ||
        f.size != static_cast<int32_t>(f.data.size())) {
      format_ok = false;
      why = std::to_string(f.width) + "x" + std::to_string(f.height) + " format " + std::to_string(f.pixelformat) +
            " stride " + std::to_string(f.row_stride) + " size " + std::to_string(f.size);
    }
  }
  report("frames_are_640x480_mjpg_with_stride_0", format_ok, why);

  int undecodable = 0, unnumbered = 0, unlike = 0, out_of_order = 0;
  int64_t last_number = -1;
  double worst_mean = 0;
  std::string decode_why, unlike_why, order_why;
  std::vector<uint8_t> grey(640 * 480);
  for (const image_t& f : frames) {
    if (f.width != 640 || f.height != 480) continue;
    try {
      slamd::decode_mjpeg_grey(f.data, f.width, f.height, grey.data(), 640);
    } catch (const slam::InputError& e) {
      ++undecodable;
      decode_why = "seq " + std::to_string(f.seq) + ": " + e.what();
      continue;
    }
    const int number = test::mjpeg_pattern_number(grey, 640, 480, 640);
    if (number < 0) {
      ++unnumbered;
      continue;
    }
    // Quality 85, 4:2:2: a clean frame is within a mean of ~1 grey level; any wrong pixel region
    // (another frame's bars, grey from missing data) moves the mean by several.
    const test::PatternDistance d = test::mjpeg_pattern_distance(grey, 640, 480, 640, static_cast<uint32_t>(number));
    worst_mean = std::max(worst_mean, d.mean);
    if (d.mean > 2.5 || d.max > 80) {
      ++unlike;
      unlike_why = "frame " + std::to_string(number) + ": mean difference " + std::to_string(d.mean) + ", largest " +
                   std::to_string(d.max);
    }
    if (number <= last_number) {
      ++out_of_order;
      order_why = "frame " + std::to_string(number) + " after " + std::to_string(last_number);
    }
    last_number = number;
  }
  std::cout << "decoded " << frames.size() - undecodable << " of " << frames.size() << " frames, last number "
            << last_number << ", worst mean difference " << worst_mean << std::endl;
  report("every_published_frame_decodes_with_slamds_decoder", !frames.empty() && undecodable == 0,
         std::to_string(undecodable) + " did not (" + decode_why + ")");
  report("every_decoded_frame_carries_a_frame_number", !frames.empty() && unnumbered == 0,
         std::to_string(unnumbered) + " without a readable number");
  report("decoded_frames_match_the_pattern_written_for_their_number", !frames.empty() && unlike == 0,
         std::to_string(unlike) + " unlike theirs (" + unlike_why + ")");
  report("frame_numbers_only_go_up", !frames.empty() && out_of_order == 0,
         std::to_string(out_of_order) + " out of order (" + order_why + ")");
  return report.exit_code();
}
