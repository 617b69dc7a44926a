// VM test program for camerad: records CAMERA and camerad's DRIVER_STATUS for a while (the scenario
// unloads and reloads the vivid driver meanwhile), then reports one PASS/FAIL line per behaviour.
//   camera_vm_check --seconds MAX --results FILE
#include <CLI/CLI.hpp>
#include <cmath>
#include <fstream>
#include <iostream>
#include <vector>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/image_t.hpp>

#include "vm_report.h"

using namespace whiskeye;

int main(int argc, char** argv) {
  CLI::App app{"camerad VM test: CAMERA checker"};
  double seconds = 14;
  std::string results_path;
  app.add_option("--seconds", seconds);
  app.add_option("--results", results_path)->required();
  CLI11_PARSE(app, argc, argv);

  struct Frame {
    int64_t utime, recv_utime, seq;
    int32_t width, height, stride, format, size, data_size;
    int distinct_bytes;
  };
  std::vector<Frame> frames;
  std::vector<driver_status_t> status;
  LcmBus bus;
  DecodeErrors errors;
  subscribe<image_t>(bus, "CAMERA", [&](const image_t& m) {
    bool seen[256] = {};
    int distinct = 0;
    for (std::size_t i = 0; i < m.data.size(); i += 97) {
      if (!seen[m.data[i]]) ++distinct;
      seen[m.data[i]] = true;
    }
    frames.push_back({m.utime, now_utime(), m.seq, m.width, m.height, m.row_stride, m.pixelformat, m.size,
                      static_cast<int32_t>(m.data.size()), distinct});
  }, errors);
  subscribe<driver_status_t>(bus, "DRIVER_STATUS", [&](const driver_status_t& m) {
    if (m.driver == "camerad") status.push_back(m);
  }, errors);
  // Until `seconds` have passed, or earlier once the stream has recovered from an outage (a gap of
  // over a second) with kRecoveredFrames frames and two status messages after it.
  constexpr std::size_t kRecoveredFrames = 8;
  const int64_t end = monotonic_us() + static_cast<int64_t>(seconds * 1e6);
  while (monotonic_us() < end) {
    bus.handle_timeout(100);
    for (std::size_t i = 1; i < frames.size(); ++i) {
      if (frames[i].recv_utime - frames[i - 1].recv_utime > 900000 && frames.size() - i >= kRecoveredFrames &&
          !status.empty() && status.back().utime > frames[i].utime + 1500000) {
        goto done;
      }
    }
  }
done:

  vm::Report report(results_path);

  report("camerad_publishes_frames", frames.size() >= 10, std::to_string(frames.size()) + " frames");
  bool format_ok = !frames.empty();
  std::string why;
  for (const Frame& f : frames) {
    if (f.width != 640 || f.height != 480 || f.format != image_t::PIXEL_FORMAT_YUYV || f.stride != 1280 ||
        f.size != 640 * 480 * 2 || f.data_size != f.size) {
      format_ok = false;
      why = std::to_string(f.width) + "x" + std::to_string(f.height) + " format " + std::to_string(f.format) +
            " stride " + std::to_string(f.stride) + " size " + std::to_string(f.size);
    }
  }
  report("frames_are_640x480_yuyv_with_stride_and_size", format_ok, why);
  bool content_ok = !frames.empty();
  for (const Frame& f : frames) content_ok = content_ok && f.distinct_bytes > 4;
  report("frames_carry_image_content", content_ok, "a frame is (nearly) uniform");
  // Buffer timestamps converted to the epoch: within a second of when the frame arrived here.
  bool time_ok = !frames.empty();
  for (const Frame& f : frames) {
    if (std::llabs(f.recv_utime - f.utime) > 1000000) {
      time_ok = false;
      why = "frame utime " + std::to_string(f.utime) + " received at " + std::to_string(f.recv_utime);
    }
  }
  report("frame_timestamps_are_epoch_utime", time_ok, why);

  // The reload shows as a gap of at least a second with frames on both sides.
  std::size_t gap_at = 0;
  for (std::size_t i = 1; i < frames.size(); ++i) {
    if (frames[i].recv_utime - frames[i - 1].recv_utime > 900000) gap_at = i;
  }
  report("frames_stop_while_the_driver_is_unloaded", gap_at > 0, "no gap in the frame stream");
  report("camerad_recovers_after_the_driver_is_reloaded", gap_at > 0 && frames.size() - gap_at >= kRecoveredFrames,
         std::to_string(gap_at > 0 ? frames.size() - gap_at : 0) + " frames after the gap");

  int64_t lost = -1, reopens = -1;
  bool degraded_seen = false, ok_at_end = false;
  for (const auto& s : status) {
    degraded_seen = degraded_seen || s.state == driver_status_t::STATE_DEGRADED;
    for (int i = 0; i < s.num_counters; ++i) {
      if (s.counter_names[i] == "device_lost") lost = s.counter_values[i];
      if (s.counter_names[i] == "reopens") reopens = s.counter_values[i];
    }
  }
  if (!status.empty()) ok_at_end = status.back().state == driver_status_t::STATE_OK;
  report("camerad_status_counts_the_loss_and_the_reopen", lost >= 1 && reopens >= 1 && status.size() >= 5,
         "device_lost " + std::to_string(lost) + " reopens " + std::to_string(reopens) + " in " +
             std::to_string(status.size()) + " status messages");
  report("camerad_status_degraded_then_ok", degraded_seen && ok_at_end, "state sequence does not show the outage");
  return report.exit_code();
}
