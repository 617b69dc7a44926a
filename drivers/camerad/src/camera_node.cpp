// camerad's state machine: open / reopen with backoff, frames → CAMERA, DRIVER_STATUS (camera_node.h).
#include "whiskeye/camerad/camera_node.h"

#include "whiskeye/common/clock.h"
#include "whiskeye/common/params.h"

#include <algorithm>
#include <chrono>
#include <sstream>
#include <thread>
#include <vector>

namespace whiskeye::camerad {

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
  if (p.reopen_max_s < p.reopen_initial_s) {
    throw ParamError(cam.source() + ": " + cam.path_of("reopen_max_s") + " must be >= " + cam.path_of("reopen_initial_s"));
  }
  cam.get("frame_timeout_s", p.frame_timeout_s, 0.1, 60.0);
  const ParamNode lcm = root.section("lcm");
  lcm.get("url", p.lcm_url);
  lcm.get("channel", p.channel);
  lcm.get("channel_status", p.channel_status);
  lcm.get("status_period_s", p.status_period_s, 0.1, 60.0);
  root.check_no_unknown_keys();
}

namespace {

// v4l2::Capture as a CaptureSession.
class V4l2Session final : public CaptureSession {
 public:
  V4l2Session(const v4l2::CaptureConfig& config, v4l2::Capture::Log log) : cap_(config, std::move(log)) {}
  v4l2::Capture::Result next(v4l2::FrameView& frame, int timeout_ms) override { return cap_.next(frame, timeout_ms); }
  const std::string& device() const override { return cap_.device(); }
  uint32_t width() const override { return cap_.width(); }
  uint32_t height() const override { return cap_.height(); }
  uint32_t pixelformat() const override { return cap_.pixelformat(); }
  double fps() const override { return cap_.fps(); }
  std::size_t num_buffers() const override { return cap_.num_buffers(); }
  const std::string& last_error() const override { return cap_.last_error(); }
  int64_t corrupt_frames() const override { return cap_.corrupt_frames(); }
  v4l2::FrameCheck last_skip() const override { return cap_.last_skip(); }
  int64_t requeue_failures() const override { return cap_.requeue_failures(); }
  bool lent_frame_overwritten() override { return cap_.lent_frame_overwritten(); }
  int64_t overwritten_frames() const override { return cap_.overwritten_frames(); }

 private:
  v4l2::Capture cap_;
};

}  // namespace

CaptureFactory v4l2_factory(std::function<void(const std::string&)> log) {
  return [log = std::move(log)](const v4l2::CaptureConfig& config) -> std::unique_ptr<CaptureSession> {
    return std::make_unique<V4l2Session>(config, log);
  };
}

Clock system_clock() {
  return Clock{[] { return monotonic_us(); }, [] { return now_utime(); },
               [](int64_t us) { std::this_thread::sleep_for(std::chrono::microseconds(us)); }};
}

CameraNode::CameraNode(Bus& bus, const Params& params, CaptureFactory open, Clock clock, Log log)
    : bus_(bus),
      params_(params),
      open_(std::move(open)),
      clock_(std::move(clock)),
      log_(std::move(log)),
      backoff_(params.reopen_initial_s, params.reopen_max_s),
      frame_timeout_us_(static_cast<int64_t>(params.frame_timeout_s * 1e6)),
      status_period_us_(static_cast<int64_t>(params.status_period_s * 1e6)),
      next_status_us_(clock_.monotonic_us() + status_period_us_) {}

int64_t CameraNode::step() {
  const int64_t now = clock_.monotonic_us();
  if (!cap_ && now >= next_open_us_) {
    open(now);
    if (!ready_sent_) {
      if (ready_hook_) ready_hook_();
      ready_sent_ = true;
    }
  }
  if (cap_) {
    read_frame();
  } else {
    clock_.sleep_us(20000);
  }
  const int64_t t = clock_.monotonic_us();
  if (t >= next_status_us_) publish_status(t);
  return t;
}

void CameraNode::open(int64_t now) {
  try {
    cap_ = open_(params_.capture);
    std::ostringstream line;
    line << "camerad: streaming " << cap_->device() << " " << cap_->width() << "x" << cap_->height() << " "
         << v4l2::fourcc_name(cap_->pixelformat()) << " at " << cap_->fps() << " fps, " << cap_->num_buffers()
         << " buffers";
    log_(LogLevel::kInfo, line.str());
    if (frames_ > 0 || device_lost_ > 0) ++reopens_;
    // The backoff is reset by the session's first frame, not by the open: a camera that opens
    // but sends nothing (USB bandwidth) is reopened ever more slowly, not every few seconds.
    last_open_error_.clear();
    // From when the device is streaming: opening it (REQBUFS, mmap, STREAMON; seconds on some UVC
    // cameras) is not time without frames.
    last_frame_us_ = clock_.monotonic_us();
    last_sequence_ = -1;
    corrupt_logged_ = 0;
    dequeue_error_logged_ = false;
    // At least three frame periods of the negotiated rate (the driver may pick a slower one
    // than asked, or the configuration ask for less than a frame per frame_timeout_s).
    const double three_periods_s = cap_->fps() > 0.0 ? 3.0 / cap_->fps() : 0.0;
    frame_timeout_us_ = static_cast<int64_t>(std::max(params_.frame_timeout_s, three_periods_s) * 1e6);
    healthy_gap_us_ = static_cast<int64_t>(std::max(1.0, three_periods_s) * 1e6);
  } catch (const v4l2::CaptureError& e) {
    ++open_failures_;
    if (e.what() != last_open_error_) log_(LogLevel::kWarning, std::string("camerad: ") + e.what() + "; retrying");
    last_open_error_ = e.what();
    next_open_us_ = now + static_cast<int64_t>(backoff_.next() * 1e6);
  }
}

void CameraNode::read_frame() {
  v4l2::FrameView f;
  auto r = cap_->next(f, 200);
  if (r == v4l2::Capture::Result::kFrame) {
    img_.data.assign(f.data, f.data + f.size);
    if (cap_->lent_frame_overwritten()) r = v4l2::Capture::Result::kSkipped;  // torn while copied: not published
  }
  if (r == v4l2::Capture::Result::kFrame) {
    img_.utime = f.utime;
    img_.seq = f.sequence;
    img_.width = static_cast<int32_t>(f.width);
    img_.height = static_cast<int32_t>(f.height);
    img_.row_stride = static_cast<int32_t>(f.stride);
    img_.pixelformat = static_cast<int32_t>(f.pixelformat);
    img_.size = static_cast<int32_t>(f.size);
    publish(bus_, params_.channel, img_);  // a failed send is counted by the bus
    ++frames_;
    ++interval_frames_;
    const double latency = static_cast<double>(clock_.now_utime() - f.utime);
    interval_latency_sum_us_ += latency;
    interval_latency_max_us_ = std::max(interval_latency_max_us_, latency);
    if (last_sequence_ >= 0 && f.sequence > last_sequence_ + 1) sequence_gaps_ += f.sequence - last_sequence_ - 1;
    if (last_sequence_ < 0) backoff_.reset();  // the session works
    last_sequence_ = f.sequence;
    last_frame_us_ = clock_.monotonic_us();
  } else if (r == v4l2::Capture::Result::kSkipped &&
             !(corrupt_logged_ & (1u << static_cast<unsigned>(cap_->last_skip())))) {
    // Not a frame: last_frame_us_ stays, so a camera sending only damaged frames gets reopened.
    log_(LogLevel::kWarning, "camerad: " + cap_->device() + ": skipping a frame " + v4l2::frame_check_name(cap_->last_skip()) +
         " (counted in corrupt_frames)");
    corrupt_logged_ |= 1u << static_cast<unsigned>(cap_->last_skip());
  } else if (r == v4l2::Capture::Result::kError) {
    ++dequeue_errors_;
    if (!dequeue_error_logged_) {
      log_(LogLevel::kWarning, "camerad: " + cap_->last_error() + " (counted in dequeue_errors)");
      dequeue_error_logged_ = true;
    }
    // The driver may keep failing at once: do not spin. No frames -> reopened after frame_timeout.
    clock_.sleep_us(10000);
  }
  if (r != v4l2::Capture::Result::kFrame &&
      (r == v4l2::Capture::Result::kGone || clock_.monotonic_us() - last_frame_us_ > frame_timeout_us_)) {
    ++device_lost_;
    log_(LogLevel::kWarning, "camerad: " + (r == v4l2::Capture::Result::kGone ? cap_->last_error() : cap_->device() + ": no frames") +
         "; closing and reopening");
    close_capture();
    next_open_us_ = clock_.monotonic_us() + static_cast<int64_t>(backoff_.next() * 1e6);
  }
}

void CameraNode::close_capture() {
  closed_corrupt_frames_ += cap_->corrupt_frames();
  closed_requeue_failures_ += cap_->requeue_failures();
  closed_overwritten_frames_ += cap_->overwritten_frames();
  cap_.reset();
}

void CameraNode::publish_status(int64_t t) {
  next_status_us_ += status_period_us_;
  if (next_status_us_ < t) next_status_us_ = t + status_period_us_;
  driver_status_t st;
  st.utime = clock_.now_utime();
  st.driver = "camerad";
  // Open is not enough: OK only while frames arrive.
  const std::string problem =
      cap_ ? v4l2::stream_problem(last_sequence_ >= 0, t - last_frame_us_, healthy_gap_us_, cap_->corrupt_frames())
           : "";
  st.state = cap_ && problem.empty() ? driver_status_t::STATE_OK : driver_status_t::STATE_DEGRADED;
  st.message = cap_ ? cap_->device() + " " + std::to_string(cap_->width()) + "x" + std::to_string(cap_->height()) +
                          " " + v4l2::fourcc_name(cap_->pixelformat()) + (problem.empty() ? "" : ": " + problem)
                    : "no camera: " + (last_open_error_.empty() ? std::string("reopening") : last_open_error_);
  const int64_t corrupt_frames = closed_corrupt_frames_ + (cap_ ? cap_->corrupt_frames() : 0);
  const int64_t requeue_failures = closed_requeue_failures_ + (cap_ ? cap_->requeue_failures() : 0);
  const int64_t overwritten_frames = closed_overwritten_frames_ + (cap_ ? cap_->overwritten_frames() : 0);
  st.counter_names = {"frames",           "device_lost",    "reopens",        "open_failures",
                      "sequence_gaps",    "corrupt_frames", "dequeue_errors", "requeue_failures",
                      "lcm_publish_errors", "overwritten_frames"};
  st.counter_values = {frames_,        device_lost_,   reopens_,         open_failures_,
                       sequence_gaps_, corrupt_frames, dequeue_errors_,  requeue_failures,
                       bus_.publish_errors(), overwritten_frames};
  st.num_counters = static_cast<int32_t>(st.counter_names.size());
  st.stat_names = {"fps", "latency_mean_us", "latency_max_us"};
  st.stat_values = {static_cast<double>(interval_frames_) / params_.status_period_s,
                    interval_frames_ ? interval_latency_sum_us_ / static_cast<double>(interval_frames_) : 0.0,
                    interval_latency_max_us_};
  st.num_stats = 3;
  publish(bus_, params_.channel_status, st);
  interval_frames_ = 0;
  interval_latency_sum_us_ = interval_latency_max_us_ = 0;
}

}  // namespace whiskeye::camerad
