// V4L2 video capture: RAII over one device, mmap streaming with >= 4 buffers, pixel format and frame
// rate negotiation (the driver's nearest mode is accepted and logged), buffer timestamps converted to
// epoch microseconds, and device loss (ENODEV / EIO) reported as Result::kGone so the caller can
// reopen. No POSIX types in the interface. Pure helpers (format names, timestamp conversion,
// reopen backoff) are separate so they are tested without a device.
#pragma once

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace whiskeye::v4l2 {

constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(a) | static_cast<uint32_t>(b) << 8 | static_cast<uint32_t>(c) << 16 |
         static_cast<uint32_t>(d) << 24;
}
inline constexpr uint32_t kYUYV = fourcc('Y', 'U', 'Y', 'V');
inline constexpr uint32_t kMJPG = fourcc('M', 'J', 'P', 'G');
inline constexpr uint32_t kGREY = fourcc('G', 'R', 'E', 'Y');

std::string fourcc_name(uint32_t code);
// "YUYV" -> code; 0 if the name is not 4 characters.
uint32_t fourcc_from_name(const std::string& name);

// A monotonic buffer timestamp (us) as epoch utime, given one simultaneous reading of both clocks.
inline int64_t monotonic_to_utime(int64_t ts_mono_us, int64_t now_mono_us, int64_t now_real_us) {
  return ts_mono_us + (now_real_us - now_mono_us);
}

// Exponential reopen backoff: initial, doubling, capped; reset() after success.
class Backoff {
 public:
  Backoff(double initial_s, double max_s) : initial_(initial_s), max_(max_s), next_(initial_s) {}
  double next() {
    const double d = next_;
    next_ = next_ * 2 > max_ ? max_ : next_ * 2;
    return d;
  }
  void reset() { next_ = initial_; }

 private:
  double initial_, max_, next_;
};

struct CaptureConfig {
  std::string device = "/dev/video0";
  std::string match_card;  // non-empty: use the first capture device whose card or driver contains this
  uint32_t width = 640;
  uint32_t height = 480;
  double fps = 5.0;
  std::vector<uint32_t> formats{kYUYV, kMJPG, kGREY};  // in order of preference
  unsigned buffers = 4;
};

class CaptureError : public std::runtime_error {
 public:
  CaptureError(const std::string& what, bool device_gone) : std::runtime_error(what), gone_(device_gone) {}
  bool device_gone() const { return gone_; }

 private:
  bool gone_;
};

struct FrameView {
  const uint8_t* data = nullptr;
  std::size_t size = 0;  // bytes used
  uint32_t width = 0, height = 0, stride = 0, pixelformat = 0;
  int64_t utime = 0;      // capture time, epoch microseconds
  uint32_t sequence = 0;  // the driver's frame counter
};

// The device to open for `config`: `device`, or the first /dev/videoN capture device matching
// `match_card`. Throws CaptureError if none matches.
std::string find_device(const CaptureConfig& config);

class Capture {
 public:
  using Log = std::function<void(const std::string&)>;
  // Opens, negotiates, maps and starts streaming. Throws CaptureError.
  Capture(const CaptureConfig& config, Log log);
  ~Capture();
  Capture(const Capture&) = delete;
  Capture& operator=(const Capture&) = delete;

  enum class Result { kFrame, kTimeout, kGone };
  // Waits up to timeout_ms for the next frame. The view stays valid until the next call.
  Result next(FrameView& frame, int timeout_ms);

  const std::string& device() const { return device_; }
  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  uint32_t stride() const { return stride_; }
  uint32_t pixelformat() const { return pixelformat_; }
  double fps() const { return fps_; }
  std::size_t num_buffers() const { return buffers_.size(); }
  const std::string& last_error() const { return last_error_; }

 private:
  void negotiate(const CaptureConfig& config);
  void map_buffers(unsigned count);
  void close_device();

  struct Buffer {
    void* start = nullptr;
    std::size_t length = 0;
  };
  Log log_;
  std::string device_;
  int fd_ = -1;
  std::vector<Buffer> buffers_;
  int held_ = -1;  // buffer lent to the caller, requeued at the next call
  bool streaming_ = false;
  uint32_t width_ = 0, height_ = 0, stride_ = 0, pixelformat_ = 0;
  double fps_ = 0;
  std::string last_error_;
};

}  // namespace whiskeye::v4l2
