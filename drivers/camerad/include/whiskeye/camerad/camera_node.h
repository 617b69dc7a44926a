// camerad's state machine, as a class a unit test drives with a fake capture and a fake clock:
//   closed:    try to open when the backoff says so; a failed open is counted (open_failures) and
//              doubles the wait (Params::reopen_initial_s .. reopen_max_s);
//   streaming: each frame → CAMERA (image_t, the pixels as captured); a damaged buffer is skipped and
//              counted (corrupt_frames); the session's first frame resets the backoff;
//   lost:      the device gone (ENODEV / EIO) or no frame for frame_timeout_s (at least three frame
//              periods) → closed, counted in device_lost; the next successful open counts a reopen.
// DRIVER_STATUS (driver "camerad") every status_period_s: OK only while frames arrive, DEGRADED
// otherwise. The daemon's main only wires: LCM, systemd notifications, signals.
#pragma once

#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"
#include "whiskeye/common/log.h"
#include "whiskeye/camera/v4l2_capture.h"

#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/image_t.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace whiskeye {
class ParamNode;
}

namespace whiskeye::camerad {

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

// Sections `camera` and `lcm` (config/camerad.yaml). Throws ParamError.
void load(const ParamNode& root, Params& p);

// One open capture session: what CameraNode needs of v4l2::Capture (whose comments say what each
// member means), so a test can stand in for the device.
class CaptureSession {
 public:
  virtual ~CaptureSession() = default;
  virtual v4l2::Capture::Result next(v4l2::FrameView& frame, int timeout_ms) = 0;
  virtual const std::string& device() const = 0;
  virtual uint32_t width() const = 0;
  virtual uint32_t height() const = 0;
  virtual uint32_t pixelformat() const = 0;
  virtual double fps() const = 0;
  virtual std::size_t num_buffers() const = 0;
  virtual const std::string& last_error() const = 0;
  virtual int64_t corrupt_frames() const = 0;
  virtual v4l2::FrameCheck last_skip() const = 0;
  virtual int64_t requeue_failures() const = 0;
  // The frame next() last returned was overwritten while read (see v4l2::Capture); a device that
  // never writes into a dequeued buffer (every vb2 driver, a test's fake) needs neither.
  virtual bool lent_frame_overwritten() { return false; }
  virtual int64_t overwritten_frames() const { return 0; }
};

// Opens a session or throws v4l2::CaptureError.
using CaptureFactory = std::function<std::unique_ptr<CaptureSession>(const v4l2::CaptureConfig&)>;
// The real device (v4l2::Capture), logging through `log`.
CaptureFactory v4l2_factory(std::function<void(const std::string&)> log);

// Time as the node sees it; system_clock() in the daemon.
struct Clock {
  std::function<int64_t()> monotonic_us;  // deadlines, backoff, silence
  std::function<int64_t()> now_utime;     // DRIVER_STATUS stamps, capture latency
  std::function<void(int64_t us)> sleep_us;
};
Clock system_clock();

// Channels: CAMERA (Params::channel) and DRIVER_STATUS (Params::channel_status) out.
class CameraNode {
 public:
  // One line, without its newline, with its priority (common/log.h): what the camera did wrong is a
  // warning, opening it is info.
  using Log = std::function<void(LogLevel, const std::string&)>;
  CameraNode(Bus& bus, const Params& params, CaptureFactory open, Clock clock, Log log);
  CameraNode(const CameraNode&) = delete;
  CameraNode& operator=(const CameraNode&) = delete;

  // Called once, right after the first attempt to open (successful or not): the daemon is running
  // its loop, and a missing camera is a status, not a failure (systemd READY).
  void set_ready_hook(std::function<void()> hook) { ready_hook_ = std::move(hook); }

  // One pass of the loop: open if closed and due, wait up to 200 ms for a frame (or sleep 20 ms when
  // closed), publish DRIVER_STATUS when due. Returns the monotonic time at its end.
  int64_t step();

  int64_t frames() const { return frames_; }

 private:
  void open(int64_t now);
  void read_frame();
  void close_capture();
  void publish_status(int64_t t);

  Bus& bus_;
  Params params_;
  CaptureFactory open_;
  Clock clock_;
  Log log_;
  std::function<void()> ready_hook_;
  bool ready_sent_ = false;

  std::unique_ptr<CaptureSession> cap_;
  v4l2::Backoff backoff_;
  int64_t next_open_us_ = 0;
  std::string last_open_error_;
  int64_t frames_ = 0, reopens_ = 0, device_lost_ = 0, open_failures_ = 0, sequence_gaps_ = 0, dequeue_errors_ = 0;
  // Totals of the capture sessions already closed; the open one adds its own (Capture counts since open).
  int64_t closed_corrupt_frames_ = 0, closed_requeue_failures_ = 0, closed_overwritten_frames_ = 0;
  // One log line per reason of skipping and capture session; corrupt_frames says how many.
  uint32_t corrupt_logged_ = 0;        // bit i: a frame skipped as FrameCheck i was logged
  bool dequeue_error_logged_ = false;  // likewise
  int64_t interval_frames_ = 0;
  double interval_latency_max_us_ = 0, interval_latency_sum_us_ = 0;
  int64_t last_frame_us_ = 0;
  int64_t last_sequence_ = -1;  // of the session's latest frame; -1: none yet this session
  int64_t frame_timeout_us_;
  // The longest silence for which DRIVER_STATUS still says OK (1 s, or three frame periods).
  int64_t healthy_gap_us_ = 1000000;
  int64_t status_period_us_;
  int64_t next_status_us_;
  image_t img_;
};

}  // namespace whiskeye::camerad
