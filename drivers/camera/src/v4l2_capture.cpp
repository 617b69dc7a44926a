// V4L2 mmap streaming capture (see v4l2_capture.h).
#include "whiskeye/camera/v4l2_capture.h"

#include <whiskeye/common/jpeg_markers.h>

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace whiskeye::v4l2 {
namespace {

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = ::ioctl(fd, request, arg);
  } while (r < 0 && errno == EINTR);
  return r;
}

bool gone_errno(int e) { return e == ENODEV || e == EIO || e == ENXIO || e == ENOENT; }

int64_t clock_us(clockid_t id) {
  timespec t;
  clock_gettime(id, &t);
  return static_cast<int64_t>(t.tv_sec) * 1000000 + t.tv_nsec / 1000;
}

// A buffer's timestamp in microseconds, on whichever clock the driver stamps with.
int64_t stamp_us(const v4l2_buffer& b) {
  return static_cast<int64_t>(b.timestamp.tv_sec) * 1000000 + b.timestamp.tv_usec;
}

std::string card_of(const v4l2_capability& cap) {
  return std::string(reinterpret_cast<const char*>(cap.card)) + " / " + reinterpret_cast<const char*>(cap.driver);
}

}  // namespace

static_assert(kBufFlagError == V4L2_BUF_FLAG_ERROR);
static_assert(kFieldNone == V4L2_FIELD_NONE);

const char* frame_check_name(FrameCheck c) {
  switch (c) {
    case FrameCheck::kUsable: return "usable";
    case FrameCheck::kErrorFlag: return "flagged as damaged by the driver";
    case FrameCheck::kShortPayload: return "shorter than stride x height";
    case FrameCheck::kEmpty: return "empty";
    case FrameCheck::kOverlong: return "longer than its buffer";
    case FrameCheck::kJpegNoStartMarker: return "without a JPEG start-of-image marker";
    case FrameCheck::kJpegBadHeader: return "whose JPEG header does not parse";
    case FrameCheck::kJpegCutShort: return "cut short (no JPEG end-of-image marker)";
    case FrameCheck::kJpegDamagedData: return "with damaged JPEG data after its header";
    case FrameCheck::kJpegWrongSize: return "whose JPEG header says another size than negotiated";
    case FrameCheck::kOverwritten: return "overwritten by the driver while it was read (torn)";
  }
  return "?";
}

bool is_raw_format(uint32_t pixelformat) { return pixelformat == kYUYV || pixelformat == kGREY; }

FrameCheck check_frame(uint32_t buffer_flags, std::size_t bytesused, std::size_t buffer_length, uint32_t pixelformat,
                       uint32_t stride, uint32_t height) {
  if (buffer_flags & kBufFlagError) return FrameCheck::kErrorFlag;
  if (bytesused == 0) return FrameCheck::kEmpty;
  if (bytesused > buffer_length) return FrameCheck::kOverlong;
  if (is_raw_format(pixelformat) && bytesused < static_cast<std::size_t>(stride) * height) {
    return FrameCheck::kShortPayload;
  }
  return FrameCheck::kUsable;
}

FrameCheck check_mjpeg(std::span<const uint8_t> frame, uint32_t width, uint32_t height) {
  jpeg::FrameSize size;
  switch (jpeg::check_structure(frame, &size)) {
    case jpeg::Structure::kWhole: break;
    case jpeg::Structure::kNoStartMarker: return FrameCheck::kJpegNoStartMarker;
    case jpeg::Structure::kBadHeader: return FrameCheck::kJpegBadHeader;
    case jpeg::Structure::kCutShort: return FrameCheck::kJpegCutShort;
    case jpeg::Structure::kDamagedData: return FrameCheck::kJpegDamagedData;
  }
  if (static_cast<uint32_t>(size.width) != width || static_cast<uint32_t>(size.height) != height) {
    return FrameCheck::kJpegWrongSize;
  }
  return FrameCheck::kUsable;
}

bool from_before_session(uint32_t sequence, int64_t timestamp_us, int64_t buffers_requested_us,
                         std::size_t dequeued_before, std::size_t ring) {
  return sequence == 0 && timestamp_us > 0 && timestamp_us <= buffers_requested_us && dequeued_before < ring;
}

std::string format_problem(const NegotiatedFormat& f, const std::vector<uint32_t>& wanted) {
  const std::string fmt = fourcc_name(f.pixelformat);
  if (std::find(wanted.begin(), wanted.end(), f.pixelformat) == wanted.end()) {
    return "the driver chose pixel format " + fmt + ", which was not asked for";
  }
  // Whole frames only: progressive, or both fields interleaved line by line (a TV input). One field
  // per buffer (top, bottom, alternate) is half a frame; fields one after the other (seq_tb/bt) are
  // not an image of row_stride lines.
  if (f.field != V4L2_FIELD_NONE && f.field != V4L2_FIELD_INTERLACED && f.field != V4L2_FIELD_INTERLACED_TB &&
      f.field != V4L2_FIELD_INTERLACED_BT) {
    return "the driver chose v4l2_field " + std::to_string(f.field) +
           ", which does not put a whole frame in a buffer line by line";
  }
  if (f.width == 0 || f.height == 0) {
    return "the driver chose an empty image (" + std::to_string(f.width) + "x" + std::to_string(f.height) + ")";
  }
  if (!is_raw_format(f.pixelformat)) return "";
  const uint64_t bytes_per_pixel = f.pixelformat == kYUYV ? 2 : 1;
  if (f.bytesperline < f.width * bytes_per_pixel) {
    return "the driver's " + fmt + " line of " + std::to_string(f.bytesperline) + " bytes is shorter than " +
           std::to_string(f.width) + " pixels x " + std::to_string(bytes_per_pixel) + " bytes";
  }
  if (f.sizeimage < static_cast<uint64_t>(f.bytesperline) * f.height) {
    return "the driver's image size " + std::to_string(f.sizeimage) + " is smaller than " +
           std::to_string(f.height) + " lines of " + std::to_string(f.bytesperline) + " bytes";
  }
  return "";
}

std::string stream_problem(bool had_frame, int64_t since_frame_us, int64_t max_gap_us,
                           int64_t session_corrupt) {
  if (had_frame && since_frame_us <= max_gap_us) return "";
  char seconds[32];
  std::snprintf(seconds, sizeof(seconds), "%.1f s", static_cast<double>(since_frame_us) / 1e6);
  if (had_frame) return std::string("no frame for ") + seconds;
  if (session_corrupt > 0) {
    return std::string("open for ") + seconds + ", only damaged frames (" + std::to_string(session_corrupt) + ")";
  }
  return std::string("open for ") + seconds + ", no frame yet";
}

std::string fourcc_name(uint32_t code) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((code >> (8 * i)) & 0xff);
    s[i] = (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

uint32_t fourcc_from_name(const std::string& n) {
  if (n.size() != 4) return 0;
  return fourcc(n[0], n[1], n[2], n[3]);
}

std::string find_device(const CaptureConfig& config) {
  if (config.match_card.empty()) return config.device;
  for (int i = 0; i < 64; ++i) {
    const std::string path = "/dev/video" + std::to_string(i);
    const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    v4l2_capability cap{};
    const bool ok = xioctl(fd, VIDIOC_QUERYCAP, &cap) == 0;
    ::close(fd);
    if (!ok) continue;
    const uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) continue;
    if (card_of(cap).find(config.match_card) != std::string::npos) return path;
  }
  throw CaptureError("no V4L2 capture device whose card or driver contains '" + config.match_card + "'", true);
}

Capture::Capture(const CaptureConfig& config, Log log) : log_(std::move(log)) {
  device_ = find_device(config);
  fd_ = ::open(device_.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int e = errno;
    throw CaptureError("open " + device_ + ": " + std::strerror(e), true);
  }
  try {
    v4l2_capability cap{};
    if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) fail("not a V4L2 device");
    const uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
      throw CaptureError(device_ + " (" + card_of(cap) + ") cannot stream video capture", false);
    }
    negotiate(config);
    map_buffers(config.buffers);
    pending_.reserve(buffers_.size());
    for (unsigned i = 0; i < buffers_.size(); ++i) {
      v4l2_buffer b{};
      b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b.memory = V4L2_MEMORY_MMAP;
      b.index = i;
      if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) fail("QBUF");
    }
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) fail("STREAMON");
    streaming_ = true;
  } catch (...) {
    close_device();
    throw;
  }
}

Capture::~Capture() { close_device(); }

void Capture::fail(const std::string& what) const {
  const int e = errno;
  throw CaptureError(device_ + ": " + what + ": " + std::strerror(e), gone_errno(e));
}

void Capture::close_device() {
  if (fd_ >= 0 && streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);
  }
  streaming_ = false;
  for (Buffer& b : buffers_) {
    if (b.start != nullptr && b.start != MAP_FAILED) ::munmap(b.start, b.length);
  }
  buffers_.clear();
  pending_.clear();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void Capture::negotiate(const CaptureConfig& config) {
  v4l2_format fmt{};
  bool found = false;
  int refusal = 0;  // an errno other than EINVAL ("not this format"), e.g. EBUSY: no format to offer yet
  for (uint32_t want : config.formats) {
    fmt = {};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = config.width;
    fmt.fmt.pix.height = config.height;
    fmt.fmt.pix.pixelformat = want;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    // TRY_FMT first: the driver answers with its nearest mode without changing anything. It is
    // optional (V4L2 spec): a driver without it (ENOTTY) is asked with S_FMT itself.
    int r = xioctl(fd_, VIDIOC_TRY_FMT, &fmt);
    if (r < 0 && errno == ENOTTY) r = xioctl(fd_, VIDIOC_S_FMT, &fmt);
    if (r == 0 && fmt.fmt.pix.pixelformat == want) {
      found = true;
      break;
    }
    if (r < 0 && gone_errno(errno)) fail("TRY_FMT");
    if (r < 0 && errno != EINVAL) refusal = errno;
  }
  if (!found) {
    std::string wanted;
    for (uint32_t f : config.formats) wanted += (wanted.empty() ? "" : ", ") + fourcc_name(f);
    throw CaptureError(device_ + " supports none of the pixel formats " + wanted +
                           (refusal ? std::string(" (VIDIOC_TRY_FMT: ") + std::strerror(refusal) + ")" : ""),
                       false);
  }
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) fail("S_FMT");
  const NegotiatedFormat got{fmt.fmt.pix.pixelformat, fmt.fmt.pix.width,     fmt.fmt.pix.height,
                             fmt.fmt.pix.bytesperline, fmt.fmt.pix.sizeimage, fmt.fmt.pix.field};
  if (const std::string problem = format_problem(got, config.formats); !problem.empty()) {
    throw CaptureError(device_ + ": " + problem, false);
  }
  width_ = fmt.fmt.pix.width;
  height_ = fmt.fmt.pix.height;
  stride_ = fmt.fmt.pix.pixelformat == kMJPG ? 0 : fmt.fmt.pix.bytesperline;
  pixelformat_ = fmt.fmt.pix.pixelformat;
  if (pixelformat_ != config.formats.front() || width_ != config.width || height_ != config.height) {
    log_("camerad: " + device_ + ": " + std::to_string(config.width) + "x" + std::to_string(config.height) + " " +
         fourcc_name(config.formats.front()) + " not supported, using the nearest mode " + std::to_string(width_) +
         "x" + std::to_string(height_) + " " + fourcc_name(pixelformat_));
  }
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator = static_cast<uint32_t>(std::lround(config.fps * 1000));
  if (xioctl(fd_, VIDIOC_S_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator > 0) {
    fps_ = static_cast<double>(parm.parm.capture.timeperframe.denominator) / parm.parm.capture.timeperframe.numerator;
  } else {
    fps_ = 0;  // driver without frame-rate control
  }
  if (std::abs(fps_ - config.fps) > 0.01) {
    log_("camerad: " + device_ + ": " + std::to_string(config.fps) + " fps not supported, the driver runs at " +
         (fps_ > 0 ? std::to_string(fps_) + " fps" : std::string("its own rate")));
  }
}

void Capture::map_buffers(unsigned count) {
  v4l2_requestbuffers req{};
  req.count = count < 4 ? 4 : count;
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0) fail("REQBUFS");
  buffers_requested_us_ = clock_us(CLOCK_MONOTONIC);
  if (req.count < 2) throw CaptureError(device_ + ": only " + std::to_string(req.count) + " buffer(s)", false);
  buffers_.resize(req.count);
  for (unsigned i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) fail("QUERYBUF");
    buffers_[i].length = b.length;
    buffers_[i].start = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
    if (buffers_[i].start == MAP_FAILED) fail("mmap");
  }
}

bool Capture::requeue_pending() {
  bool gone = false;
  requeue_failures_ += requeue_all(pending_, [&](uint32_t index) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = index;
    if (xioctl(fd_, VIDIOC_QBUF, &b) == 0) return true;
    const int e = errno;
    last_error_ = device_ + ": QBUF: " + std::strerror(e);
    gone = gone || gone_errno(e);
    return false;
  });
  return !gone;
}

Capture::Result Capture::next(FrameView& frame, int timeout_ms) {
  if (fd_ < 0) return Result::kGone;
  if (!requeue_pending()) return Result::kGone;
  pollfd p{fd_, POLLIN, 0};
  const int n = ::poll(&p, 1, timeout_ms);
  if (n == 0 || (n < 0 && errno == EINTR)) return Result::kTimeout;
  if (n < 0 || (p.revents & (POLLERR | POLLHUP | POLLNVAL))) {
    // A vanished device reports POLLERR; DQBUF below tells why.
    if (!(p.revents & POLLIN)) {
      v4l2_buffer b{};
      b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b.memory = V4L2_MEMORY_MMAP;
      if (xioctl(fd_, VIDIOC_DQBUF, &b) < 0 && errno != EAGAIN) {
        const int e = errno;
        last_error_ = device_ + ": " + std::strerror(e);
        return Result::kGone;
      }
      last_error_ = device_ + ": poll error";
      return Result::kGone;
    }
  }
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_DQBUF, &b) < 0) {
    const int e = errno;
    if (e == EAGAIN) return Result::kTimeout;
    last_error_ = device_ + ": DQBUF: " + std::strerror(e);
    return gone_errno(e) ? Result::kGone : Result::kError;
  }
  if (b.index >= buffers_.size()) {  // videobuf2 never does this; nothing to requeue or read
    last_error_ = device_ + ": DQBUF returned buffer " + std::to_string(b.index) + " of " +
                  std::to_string(buffers_.size());
    return Result::kError;
  }
  pending_.push_back(b.index);  // lent to the caller (or skipped): back to the driver at the next call
  if (from_before_session(b.sequence, stamp_us(b), buffers_requested_us_, dequeued_++, buffers_.size())) {
    if (!from_before_logged_) {
      log_("camerad: " + device_ + ": skipping a buffer from before the stream started (sequence 0, stamped " +
           "before camerad asked for its buffers, as v4l2loopback re-initialises them): not a frame, not damage");
      from_before_logged_ = true;
    }
    return next(frame, timeout_ms);  // gives it back first; at most `ring` such buffers a session
  }
  const auto* data = static_cast<const uint8_t*>(buffers_[b.index].start);
  FrameCheck c = check_frame(b.flags, b.bytesused, buffers_[b.index].length, pixelformat_, stride_, height_);
  if (c == FrameCheck::kUsable && pixelformat_ == kMJPG) c = check_mjpeg({data, b.bytesused}, width_, height_);
  if (c != FrameCheck::kUsable) {
    if (!overwritten(b.index, b.sequence)) {  // a torn frame counts as such, whatever its bytes looked like
      ++corrupt_frames_;
      last_skip_ = c;
    }
    return requeue_pending() ? Result::kSkipped : Result::kGone;
  }
  lent_index_ = b.index;
  lent_sequence_ = b.sequence;
  frame.data = data;
  frame.size = b.bytesused;
  frame.width = width_;
  frame.height = height_;
  frame.stride = stride_;
  frame.pixelformat = pixelformat_;
  frame.sequence = b.sequence;
  const int64_t ts = stamp_us(b);
  if ((b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC && ts > 0) {
    frame.utime = monotonic_to_utime(ts, clock_us(CLOCK_MONOTONIC), clock_us(CLOCK_REALTIME));
  } else {
    frame.utime = clock_us(CLOCK_REALTIME);  // driver without usable timestamps: dequeue time
  }
  return Result::kFrame;
}

bool Capture::lent_frame_overwritten() { return overwritten(lent_index_, lent_sequence_); }

bool Capture::overwritten(uint32_t index, uint32_t sequence) {
  v4l2_buffer q{};
  q.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  q.memory = V4L2_MEMORY_MMAP;
  q.index = index;
  if (xioctl(fd_, VIDIOC_QUERYBUF, &q) < 0 || q.sequence == sequence) return false;  // a vanished device: next() says
  ++corrupt_frames_;
  ++overwritten_frames_;
  last_skip_ = FrameCheck::kOverwritten;
  return true;
}

}  // namespace whiskeye::v4l2
