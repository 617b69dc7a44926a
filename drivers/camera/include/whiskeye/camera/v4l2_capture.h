// V4L2 video capture: RAII over one device, mmap streaming with >= 4 buffers, pixel format and frame
// rate negotiation (the driver's nearest mode is accepted and logged), buffer timestamps converted to
// epoch microseconds, and device loss (ENODEV / EIO) reported as Result::kGone so the caller can
// reopen. No POSIX types in the interface. Pure helpers (format names, timestamp conversion,
// reopen backoff) are separate so they are tested without a device.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
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

// Whether a dequeued buffer holds a whole frame. The driver flags a frame it knows is damaged
// (V4L2_BUF_FLAG_ERROR: lost USB packets, a resync); an uncompressed frame (YUYV, GREY) shorter than
// stride x height is truncated; an empty buffer holds nothing; one that says it holds more than its
// mapped length cannot be read. A compressed frame (MJPG) has no fixed size; its bytes are read
// by check_mjpeg() below. Such buffers are requeued, counted (camerad's corrupt_frames) and never
// published.
enum class FrameCheck {
  kUsable, kErrorFlag, kShortPayload, kEmpty, kOverlong,
  // MJPG only (check_mjpeg):
  kJpegNoStartMarker, kJpegBadHeader, kJpegCutShort, kJpegDamagedData, kJpegWrongSize,
  // Written again by the driver while it was read (Capture::lent_frame_overwritten()).
  kOverwritten
};
const char* frame_check_name(FrameCheck c);
inline constexpr uint32_t kBufFlagError = 0x00000040;  // V4L2_BUF_FLAG_ERROR (checked in the source)
bool is_raw_format(uint32_t pixelformat);
FrameCheck check_frame(uint32_t buffer_flags, std::size_t bytesused, std::size_t buffer_length, uint32_t pixelformat,
                       uint32_t stride, uint32_t height);
// An MJPEG frame's bytes, read without decoding (whiskeye::jpeg::check_structure, one pass over the
// data): a frame cut short (no end-of-image marker), a header that does not parse, data after the
// header holding markers no JPEG holds there (garbage), or a JPEG whose header claims another size
// than the negotiated width x height. Garbage that happens to hold only legal markers passes; slamd's
// decoder refuses it (decode errors in SLAM_STATUS).
FrameCheck check_mjpeg(std::span<const uint8_t> frame, uint32_t width, uint32_t height);

// Whether a dequeued buffer holds no frame of this session. v4l2loopback 0.12.7 re-initialises every
// buffer of its ring when a reader asks for buffers (VIDIOC_REQBUFS: sequence 0, bytesused the
// format's sizeimage, stamped at that moment) while its writer goes on filling them one by one, so a
// reader joining a running writer is first handed the newest frame written before it asked, under a
// number, time and size that are not that frame's: a whole JPEG followed by an older, longer frame's
// last bytes, which check_mjpeg() rightly calls damaged. Such a buffer has sequence 0, a timestamp
// (microseconds, CLOCK_MONOTONIC as v4l2loopback stamps) no later than `buffers_requested_us`, when
// the session's VIDIOC_REQBUFS returned, and is among the session's first `ring` dequeued ones
// (`dequeued_before` came earlier). A vb2 driver (UVC, vivid) fills and stamps a buffer only after
// STREAMON, so none of its frames is such a buffer; a timestamp of 0 (none) or from the epoch
// (CLOCK_REALTIME) never is; a driver with its own clock loses at most its frame numbered 0.
bool from_before_session(uint32_t sequence, int64_t timestamp_us, int64_t buffers_requested_us,
                         std::size_t dequeued_before, std::size_t ring);

// What the driver settled on when asked for a format (VIDIOC_S_FMT's answer).
inline constexpr uint32_t kFieldNone = 1;  // V4L2_FIELD_NONE: progressive (checked in the source)
struct NegotiatedFormat {
  uint32_t pixelformat = 0;
  uint32_t width = 0, height = 0;
  uint32_t bytesperline = 0, sizeimage = 0;
  uint32_t field = kFieldNone;
};
// "" if frames in this format can be read as camerad publishes them, else why not, naming the
// values: a pixel format that was not asked for, a field order that does not put a whole frame in a
// buffer line by line (one field per buffer, or the fields one after the other; progressive and
// interleaved fields are fine), an empty image, a raw line shorter than width x bytes per pixel, or
// an image smaller than its lines.
std::string format_problem(const NegotiatedFormat& f, const std::vector<uint32_t>& wanted);

// camerad's health while a capture session is open: OK only once a frame has arrived, and while
// frames go on arriving (a camera that opens and sends nothing is not OK). `had_frame`: a frame was
// published since the open, the last one `since_frame_us` ago (else the open was);
// `max_gap_us` is the longest silence still healthy; `session_corrupt` buffers were skipped as
// damaged. Returns "" when healthy, else what is wrong, for DRIVER_STATUS's message.
std::string stream_problem(bool had_frame, int64_t since_frame_us, int64_t max_gap_us,
                           int64_t session_corrupt);

// Gives every pending (dequeued) buffer back through `qbuf(index)` (true on success). A buffer that
// qbuf refuses stays in `pending` for the next try instead of being forgotten: a lost buffer would
// shrink the driver's ring for the rest of the session. Returns the number of refusals.
template <typename QBuf>
int requeue_all(std::vector<uint32_t>& pending, QBuf&& qbuf) {
  std::size_t kept = 0;
  for (const uint32_t index : pending) {
    if (!qbuf(index)) pending[kept++] = index;
  }
  const int refused = static_cast<int>(kept);
  pending.resize(kept);
  return refused;
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

  // kSkipped: a buffer arrived but failed check_frame(); it went straight back to the driver and is
  // counted in corrupt_frames() (last_skip() says why). kError: dequeuing failed while the device
  // is still there (last_error() says how); the caller counts it and should not retry at once.
  enum class Result { kFrame, kTimeout, kGone, kSkipped, kError };
  // Waits up to timeout_ms for the next frame. The view stays valid until the next call. A buffer
  // holding no frame of this session (from_before_session()) goes straight back to the driver, is
  // logged once and counted nowhere, and the wait goes on: it is neither a frame nor damage.
  Result next(FrameView& frame, int timeout_ms);

  const std::string& device() const { return device_; }
  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }
  uint32_t stride() const { return stride_; }
  uint32_t pixelformat() const { return pixelformat_; }
  double fps() const { return fps_; }
  std::size_t num_buffers() const { return buffers_.size(); }
  const std::string& last_error() const { return last_error_; }
  // A driver owns a buffer again only once it is queued back, and vb2 drivers keep to that;
  // v4l2loopback writes its ring round regardless, so a frame read slowly (more than the ring's
  // length of frame periods) can be overwritten while it is read: torn. True if the driver says the
  // buffer of the frame last returned by next() holds another frame now (its sequence number
  // changed since it was dequeued); that frame is then counted in corrupt_frames() and
  // overwritten_frames() and must not be used. Call it after the frame's bytes were copied.
  bool lent_frame_overwritten();
  // Buffers skipped by check_frame() or found overwritten since open; of them, overwritten ones.
  int64_t corrupt_frames() const { return corrupt_frames_; }
  int64_t overwritten_frames() const { return overwritten_frames_; }
  FrameCheck last_skip() const { return last_skip_; }
  // QBUF calls that failed since open. The buffer is kept and given back at the next call, so a
  // transient failure does not shrink the buffer ring.
  int64_t requeue_failures() const { return requeue_failures_; }

 private:
  void negotiate(const CaptureConfig& config);
  void map_buffers(unsigned count);
  void close_device();
  // Throws a CaptureError "<device>: <what>: <strerror(errno)>", gone if errno says the device is.
  // errno is read first, before building the message can change it.
  [[noreturn]] void fail(const std::string& what) const;
  // Gives every dequeued buffer back to the driver; false if the device is gone.
  bool requeue_pending();

  struct Buffer {
    void* start = nullptr;
    std::size_t length = 0;
  };
  Log log_;
  std::string device_;
  int fd_ = -1;
  std::vector<Buffer> buffers_;
  // Dequeued buffers not yet given back (the one lent to the caller, or one whose QBUF failed):
  // requeued at the next call. At most one entry per buffer.
  std::vector<uint32_t> pending_;
  // True if buffer `index` holds another frame than `sequence` (QUERYBUF); counts it if so.
  bool overwritten(uint32_t index, uint32_t sequence);
  int64_t buffers_requested_us_ = 0;  // CLOCK_MONOTONIC when VIDIOC_REQBUFS returned
  std::size_t dequeued_ = 0;          // buffers dequeued since open
  bool from_before_logged_ = false;
  int64_t corrupt_frames_ = 0;
  int64_t overwritten_frames_ = 0;
  int64_t requeue_failures_ = 0;
  uint32_t lent_index_ = 0, lent_sequence_ = 0;  // the frame next() last returned
  FrameCheck last_skip_ = FrameCheck::kUsable;
  bool streaming_ = false;
  uint32_t width_ = 0, height_ = 0, stride_ = 0, pixelformat_ = 0;
  double fps_ = 0;
  std::string last_error_;
};

}  // namespace whiskeye::v4l2
