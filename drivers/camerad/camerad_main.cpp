// camerad: V4L2 camera -> CAMERA (image_t, the pixels as captured) and DRIVER_STATUS at 1 Hz.
// The device disappearing (unplugged, driver reloaded: ENODEV / EIO) is not fatal: camerad closes it
// and reopens with exponential backoff, reporting DEGRADED meanwhile. Bad configuration is the only
// startup failure.
#include <signal.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <iostream>
#include <memory>
#include <thread>

#include <whiskeye/common/bus.h>
#include <whiskeye/common/channels.h>
#include <whiskeye/common/cli.h>
#include <whiskeye/common/clock.h>
#include <whiskeye/common/log.h>
#include <whiskeye/common/params.h>
#include <whiskeye/common/service.h>
#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/image_t.hpp>

#include "whiskeye/drivers/v4l2_capture.h"

namespace {

using namespace whiskeye;

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

struct Params {
  v4l2::CaptureConfig capture;
  double reopen_initial_s = 0.2;
  double reopen_max_s = 5.0;
  double frame_timeout_s = 2.0;  // no frame for this long while streaming: reopen
  std::string lcm_url;
  std::string channel = channels::kCamera;
  std::string channel_status = channels::kDriverStatus;
  double status_period_s = 1.0;
};

void load(const ParamNode& root, Params& p) {
  const ParamNode cam = root.section("camera");
  cam.get("device", p.capture.device);
  cam.get("match_card", p.capture.match_card);
  cam.get("width", p.capture.width, 16u, 8192u);
  cam.get("height", p.capture.height, 16u, 8192u);
  cam.get("fps", p.capture.fps, 0.1, 240.0);
  cam.get("buffers", p.capture.buffers, 4u, 32u);
  std::vector<std::string> formats;
  for (uint32_t f : p.capture.formats) formats.push_back(v4l2::fourcc_name(f));
  cam.get("formats", formats);
  p.capture.formats.clear();
  for (const std::string& f : formats) {
    if (f != "YUYV" && f != "MJPG" && f != "GREY") {
      throw ParamError(cam.path_of("formats") + ": '" + f + "' is not one of YUYV, MJPG, GREY");
    }
    p.capture.formats.push_back(v4l2::fourcc_from_name(f));
  }
  if (p.capture.formats.empty()) throw ParamError(cam.path_of("formats") + " is empty");
  cam.get("reopen_initial_s", p.reopen_initial_s, 0.01, 10.0);
  cam.get("reopen_max_s", p.reopen_max_s, 0.01, 60.0);
  cam.get("frame_timeout_s", p.frame_timeout_s, 0.1, 60.0);
  const ParamNode lcm = root.section("lcm");
  lcm.get("url", p.lcm_url);
  lcm.get("channel", p.channel);
  lcm.get("channel_status", p.channel_status);
  lcm.get("status_period_s", p.status_period_s, 0.1, 60.0);
  root.check_no_unknown_keys();
}

int run(const Params& p) {
  ServiceNotifier service("camerad", monotonic_us());  // a malformed WHISKEYE_FAULT_INJECT: exit 1
  std::unique_ptr<LcmBus> bus;
  try {
    bus = std::make_unique<LcmBus>(p.lcm_url);
  } catch (const std::exception& e) {
    log_error(std::string("camerad: ") + e.what());
    return 1;
  }
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);

  // What Capture logs is the driver refusing what was asked (a size, a rate): warnings.
  auto log = [](const std::string& line) { log_warning(line); };
  std::unique_ptr<v4l2::Capture> cap;
  v4l2::Backoff backoff(p.reopen_initial_s, p.reopen_max_s);
  int64_t next_open_us = 0;
  std::string last_open_error;
  int64_t frames = 0, reopens = 0, device_lost = 0, open_failures = 0, sequence_gaps = 0, dequeue_errors = 0;
  // Totals of the capture sessions already closed; the open one adds its own (Capture counts since open).
  int64_t closed_corrupt_frames = 0, closed_requeue_failures = 0;
  // One log line per reason of skipping and capture session; corrupt_frames says how many.
  uint32_t corrupt_logged = 0;  // bit i: a frame skipped as FrameCheck i was logged
  bool dequeue_error_logged = false;  // likewise
  auto close_capture = [&] {
    closed_corrupt_frames += cap->corrupt_frames();
    closed_requeue_failures += cap->requeue_failures();
    cap.reset();
  };
  int64_t interval_frames = 0;
  double interval_latency_max_us = 0, interval_latency_sum_us = 0;
  int64_t last_frame_us = 0;
  int64_t last_sequence = -1;  // of the session's latest frame; -1: none yet this session
  int64_t frame_timeout_us = static_cast<int64_t>(p.frame_timeout_s * 1e6);
  // The longest silence for which DRIVER_STATUS still says OK (1 s, or three frame periods).
  int64_t healthy_gap_us = 1000000;
  const int64_t status_period_us = static_cast<int64_t>(p.status_period_s * 1e6);
  int64_t next_status_us = monotonic_us() + status_period_us;
  bool ready_sent = false;
  image_t img;

  while (!g_stop.load()) {
    const int64_t now = monotonic_us();
    if (!cap && now >= next_open_us) {
      try {
        cap = std::make_unique<v4l2::Capture>(p.capture, log);
        std::cerr << "camerad: streaming " << cap->device() << " " << cap->width() << "x" << cap->height() << " "
                  << v4l2::fourcc_name(cap->pixelformat()) << " at " << cap->fps() << " fps, " << cap->num_buffers()
                  << " buffers\n";
        if (frames > 0 || device_lost > 0) ++reopens;
        // The backoff is reset by the session's first frame, not by the open: a camera that opens
        // but sends nothing (USB bandwidth) is reopened ever more slowly, not every few seconds.
        last_open_error.clear();
        last_frame_us = now;
        last_sequence = -1;
        corrupt_logged = 0;
        dequeue_error_logged = false;
        // At least three frame periods of the negotiated rate (the driver may pick a slower one
        // than asked, or the configuration ask for less than a frame per frame_timeout_s).
        const double three_periods_s = cap->fps() > 0.0 ? 3.0 / cap->fps() : 0.0;
        frame_timeout_us = static_cast<int64_t>(std::max(p.frame_timeout_s, three_periods_s) * 1e6);
        healthy_gap_us = static_cast<int64_t>(std::max(1.0, three_periods_s) * 1e6);
      } catch (const v4l2::CaptureError& e) {
        ++open_failures;
        if (e.what() != last_open_error) log_warning(std::string("camerad: ") + e.what() + "; retrying");
        last_open_error = e.what();
        next_open_us = now + static_cast<int64_t>(backoff.next() * 1e6);
      }
      if (!ready_sent) {
        service.ready();  // ready = running its loop; a missing camera is a status, not a failure
        ready_sent = true;
      }
    }
    if (cap) {
      v4l2::FrameView f;
      const auto r = cap->next(f, 200);
      if (r == v4l2::Capture::Result::kFrame) {
        img.utime = f.utime;
        img.seq = f.sequence;
        img.width = static_cast<int32_t>(f.width);
        img.height = static_cast<int32_t>(f.height);
        img.row_stride = static_cast<int32_t>(f.stride);
        img.pixelformat = static_cast<int32_t>(f.pixelformat);
        img.size = static_cast<int32_t>(f.size);
        img.data.assign(f.data, f.data + f.size);
        publish(*bus, p.channel, img);  // a failed send is counted by the bus
        ++frames;
        ++interval_frames;
        const double latency = static_cast<double>(now_utime() - f.utime);
        interval_latency_sum_us += latency;
        interval_latency_max_us = std::max(interval_latency_max_us, latency);
        if (last_sequence >= 0 && f.sequence > last_sequence + 1) sequence_gaps += f.sequence - last_sequence - 1;
        if (last_sequence < 0) backoff.reset();  // the session works
        last_sequence = f.sequence;
        last_frame_us = monotonic_us();
      } else if (r == v4l2::Capture::Result::kSkipped &&
                 !(corrupt_logged & (1u << static_cast<unsigned>(cap->last_skip())))) {
        // Not a frame: last_frame_us stays, so a camera sending only damaged frames gets reopened.
        log_warning("camerad: " + cap->device() + ": skipping a frame " + v4l2::frame_check_name(cap->last_skip()) +
                    " (counted in corrupt_frames)");
        corrupt_logged |= 1u << static_cast<unsigned>(cap->last_skip());
      } else if (r == v4l2::Capture::Result::kError) {
        ++dequeue_errors;
        if (!dequeue_error_logged) {
          log_warning("camerad: " + std::string(cap->last_error()) + " (counted in dequeue_errors)");
          dequeue_error_logged = true;
        }
        // The driver may keep failing at once: do not spin. No frames -> reopened after frame_timeout.
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      if (r != v4l2::Capture::Result::kFrame &&
          (r == v4l2::Capture::Result::kGone ||
           monotonic_us() - last_frame_us > frame_timeout_us)) {
        ++device_lost;
        log_warning("camerad: " +
                    (r == v4l2::Capture::Result::kGone ? std::string(cap->last_error()) : cap->device() + ": no frames") +
                    "; closing and reopening");
        close_capture();
        next_open_us = monotonic_us() + static_cast<int64_t>(backoff.next() * 1e6);
      }
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }

    const int64_t t = monotonic_us();
    if (t >= next_status_us) {
      next_status_us += status_period_us;
      if (next_status_us < t) next_status_us = t + status_period_us;
      driver_status_t st;
      st.utime = now_utime();
      st.driver = "camerad";
      // Open is not enough: OK only while frames arrive.
      const std::string problem =
          cap ? v4l2::stream_problem(last_sequence >= 0, t - last_frame_us, healthy_gap_us, cap->corrupt_frames())
              : "";
      st.state = cap && problem.empty() ? driver_status_t::STATE_OK : driver_status_t::STATE_DEGRADED;
      st.message = cap ? cap->device() + " " + std::to_string(cap->width()) + "x" + std::to_string(cap->height()) +
                             " " + v4l2::fourcc_name(cap->pixelformat()) + (problem.empty() ? "" : ": " + problem)
                       : "no camera: " + (last_open_error.empty() ? std::string("reopening") : last_open_error);
      const int64_t corrupt_frames = closed_corrupt_frames + (cap ? cap->corrupt_frames() : 0);
      const int64_t requeue_failures = closed_requeue_failures + (cap ? cap->requeue_failures() : 0);
      st.counter_names = {"frames",           "device_lost",    "reopens",        "open_failures",
                          "sequence_gaps",    "corrupt_frames", "dequeue_errors", "requeue_failures",
                          "lcm_publish_errors"};
      st.counter_values = {frames,           device_lost,    reopens,        open_failures,
                           sequence_gaps,    corrupt_frames, dequeue_errors, requeue_failures,
                           bus->publish_errors()};
      st.num_counters = static_cast<int32_t>(st.counter_names.size());
      st.stat_names = {"fps", "latency_mean_us", "latency_max_us"};
      st.stat_values = {static_cast<double>(interval_frames) / p.status_period_s,
                        interval_frames ? interval_latency_sum_us / static_cast<double>(interval_frames) : 0.0,
                        interval_latency_max_us};
      st.num_stats = 3;
      publish(*bus, p.channel_status, st);
      interval_frames = 0;
      interval_latency_sum_us = interval_latency_max_us = 0;
    }
    service.keep_alive(t);
    // Test-only (WHISKEYE_FAULT_INJECT): a stuck capture loop, to prove the watchdog notices.
    service.stall_if_injected(t, [] { return g_stop.load(); });
  }
  service.stopping();
  std::cerr << "camerad: stopped after " << frames << " frames\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cli::Program program("camerad", "camerad: V4L2 camera capture (mmap streaming) published as CAMERA over LCM");
  CLI::App& app = program.app();
  std::string config_path, device, lcm_url;
  bool print_config = false;
  program.add_config(config_path, "camerad YAML (config/camerad.yaml); defaults without it");
  app.add_option("-d,--device", device, "video device, overrides camera.device (and clears camera.match_card)");
  program.add_lcm_url(lcm_url)->description("LCM URL, overrides lcm.url (default: $LCM_DEFAULT_URL, or LCM's default)");
  program.add_print_config(print_config);
  return program.run(argc, argv, [&] {
    // The file, then the command line's overrides: what is printed is what runs.
    ParamNode root = config_path.empty() ? ParamNode::empty() : ParamNode::from_file(config_path);
    if (!device.empty()) {
      root.set_override("camera.device", device, "--device");
      root.set_override("camera.match_card", "", "--device");
    }
    if (!lcm_url.empty()) root.set_override("lcm.url", lcm_url, "--lcm-url");
    Params p;
    load(root, p);  // a ParamError: exit 2
    if (print_config) {
      std::cout << root.dump();
      return 0;
    }
    std::cerr << root.dump();
    return run(p);
  });
}
