// Visual template: every pixel format ends as a float greyscale image in [0, 1], which is cropped,
// block-averaged (OpenCV INTER_AREA = exact area averaging, also for non-integer ratios) and
// normalised. See visual_template.h.
#include "whiskeye/slam/visual_template.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstddef>
#include <cstdio>
#include <span>
#include <string>
#include <utility>

// libjpeg's C API, after <cstdio> (it needs FILE).
#include <jpeglib.h>

namespace whiskeye::slam {

void load(const ParamNode& n, VisualParams& p) {
  n.get("crop_x", p.crop_x, 0, 100000);
  n.get("crop_y", p.crop_y, 0, 100000);
  n.get("crop_width", p.crop_width, 0, 100000);
  n.get("crop_height", p.crop_height, 0, 100000);
  n.get("template_width", p.template_width, 4, 1024);
  n.get("template_height", p.template_height, 1, 1024);
  n.get("global_normalisation", p.global_normalisation, 0.0, 1.0);
  n.get("patch_radius", p.patch_radius, 0, 32);
}

namespace {

std::string fourcc_text(uint32_t f) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((f >> (8 * i)) & 0xff);
    s += (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

void check_raw(const ImageView& im, int bytes_per_pixel) {
  if (im.width <= 0 || im.height <= 0) {
    throw InputError("image: bad size " + std::to_string(im.width) + "x" + std::to_string(im.height));
  }
  const int64_t row_bytes = static_cast<int64_t>(im.width) * bytes_per_pixel;
  if (im.row_stride < row_bytes) {
    throw InputError("image: row_stride " + std::to_string(im.row_stride) + " < " + std::to_string(row_bytes) +
                     " bytes for " + fourcc_text(im.pixelformat) + " width " + std::to_string(im.width));
  }
  const int64_t need = static_cast<int64_t>(im.row_stride) * (im.height - 1) + row_bytes;
  if (static_cast<int64_t>(im.data.size()) < need) {
    throw InputError("image: " + std::to_string(im.data.size()) + " bytes of data, " + std::to_string(need) +
                     " needed for " + std::to_string(im.width) + "x" + std::to_string(im.height) + " " +
                     fourcc_text(im.pixelformat));
  }
}

// The frame size in a JPEG's header (its first SOF segment), or {0, 0} when there is none before the
// scan. cv::imdecode takes the size from there, not from the message: a few hundred bytes can claim
// 32752 x 32752 pixels (gigabytes, seconds of CPU), so the header is read first.
std::pair<int, int> jpeg_size(std::span<const uint8_t> d) {
  if (d.size() < 4 || d[0] != 0xff || d[1] != 0xd8) return {0, 0};
  std::size_t pos = 2;
  while (pos + 4 <= d.size()) {
    if (d[pos] != 0xff) return {0, 0};
    const uint8_t marker = d[pos + 1];
    if (marker == 0xff) {  // fill byte
      ++pos;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) {  // no length field
      pos += 2;
      continue;
    }
    const std::size_t length = (std::size_t{d[pos + 2]} << 8) | d[pos + 3];
    const bool sof = marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
    if (sof) {
      if (length < 7 || pos + 9 > d.size()) return {0, 0};
      return {(d[pos + 7] << 8) | d[pos + 8], (d[pos + 5] << 8) | d[pos + 6]};
    }
    if (marker == 0xda || marker == 0xd9 || length < 2) return {0, 0};  // scan or end before a frame header
    pos += 2 + length;
  }
  return {0, 0};
}

// Whether a JPEG ends with its end-of-image marker (FF D9), ignoring zero padding after it (some UVC
// cameras pad their buffers). A frame cut off in transfer has none; OpenCV would decode it anyway,
// greying out what is missing, and that grey would become a template.
bool ends_with_eoi(std::span<const uint8_t> d) {
  std::size_t end = d.size();
  while (end > 0 && d[end - 1] == 0x00) --end;
  return end >= 2 && d[end - 2] == 0xff && d[end - 1] == 0xd9;
}

// MJPEG frames are decoded with libjpeg directly (as OpenCV's imdecode does underneath) so that its
// warnings are seen: a frame cut short in transfer with an end-of-image marker appended decodes
// "successfully", greyed out where data is missing, with only libjpeg's own unprefixed "Corrupt JPEG
// data: premature end of data segment" on stderr. Here any warning refuses the frame, with libjpeg's
// text in the reason, and nothing is written to stderr. The state is plain C data: libjpeg reports
// fatal errors by longjmp, which must not cross objects with destructors.
struct JpegDecoder {
  jpeg_decompress_struct cinfo;
  jpeg_error_mgr err;
  std::jmp_buf jump;
  char error[JMSG_LENGTH_MAX];
  char warning[JMSG_LENGTH_MAX];
};

void jpeg_on_error(j_common_ptr c) {
  auto* d = reinterpret_cast<JpegDecoder*>(reinterpret_cast<char*>(c->err) - offsetof(JpegDecoder, err));
  (*c->err->format_message)(c, d->error);
  std::longjmp(d->jump, 1);
}

void jpeg_on_message(j_common_ptr c, int level) {
  if (level >= 0) return;  // trace messages
  auto* d = reinterpret_cast<JpegDecoder*>(reinterpret_cast<char*>(c->err) - offsetof(JpegDecoder, err));
  if (c->err->num_warnings++ == 0) (*c->err->format_message)(c, d->warning);
}

void jpeg_no_output(j_common_ptr) {}

enum class JpegResult { kOk, kError, kWarning, kWrongSize };

// Decodes `data` as greyscale into `out` (width x height, `stride` bytes per row).
JpegResult decode_jpeg_grey(JpegDecoder* d, const uint8_t* data, std::size_t size, uint8_t* out, std::size_t stride,
                            int width, int height) {
  d->error[0] = d->warning[0] = '\0';
  d->cinfo.err = jpeg_std_error(&d->err);
  d->err.error_exit = jpeg_on_error;
  d->err.emit_message = jpeg_on_message;
  d->err.output_message = jpeg_no_output;
  jpeg_create_decompress(&d->cinfo);
  if (setjmp(d->jump) != 0) {
    jpeg_destroy_decompress(&d->cinfo);
    return JpegResult::kError;
  }
  jpeg_mem_src(&d->cinfo, data, static_cast<unsigned long>(size));
  jpeg_read_header(&d->cinfo, TRUE);
  d->cinfo.out_color_space = JCS_GRAYSCALE;
  jpeg_start_decompress(&d->cinfo);
  if (static_cast<int>(d->cinfo.output_width) != width || static_cast<int>(d->cinfo.output_height) != height ||
      d->cinfo.output_components != 1) {
    jpeg_destroy_decompress(&d->cinfo);
    return JpegResult::kWrongSize;
  }
  while (d->cinfo.output_scanline < d->cinfo.output_height) {
    JSAMPROW row = out + static_cast<std::size_t>(d->cinfo.output_scanline) * stride;
    jpeg_read_scanlines(&d->cinfo, &row, 1);
  }
  jpeg_finish_decompress(&d->cinfo);
  const bool warned = d->err.num_warnings > 0;
  jpeg_destroy_decompress(&d->cinfo);
  return warned ? JpegResult::kWarning : JpegResult::kOk;
}

// Decoding costs what the header claims, not what the message weighs: a 331-byte JPEG claiming
// 10000 x 10000 took 2 s and 550 MB. No camera of this robot comes near 16.8 MP.
constexpr int64_t kMaxJpegPixels = int64_t{4096} * 4096;

cv::Mat to_grey8(const ImageView& im) {
  // OpenCV wants a non-const pointer for a header over foreign data; it is only read.
  auto* data = const_cast<uint8_t*>(im.data.data());
  const auto stride = static_cast<size_t>(im.row_stride);
  cv::Mat grey;
  switch (im.pixelformat) {
    case kPixGrey:
      check_raw(im, 1);
      return cv::Mat(im.height, im.width, CV_8UC1, data, stride);
    case kPixYuyv:
      check_raw(im, 2);
      cv::cvtColor(cv::Mat(im.height, im.width, CV_8UC2, data, stride), grey, cv::COLOR_YUV2GRAY_YUYV);
      return grey;
    case kPixRgb24:
      check_raw(im, 3);
      cv::cvtColor(cv::Mat(im.height, im.width, CV_8UC3, data, stride), grey, cv::COLOR_RGB2GRAY);
      return grey;
    case kPixBgr24:
      check_raw(im, 3);
      cv::cvtColor(cv::Mat(im.height, im.width, CV_8UC3, data, stride), grey, cv::COLOR_BGR2GRAY);
      return grey;
    case kPixMjpeg: {
      if (im.data.empty()) throw InputError("image: empty MJPEG frame");
      const auto [width, height] = jpeg_size(im.data);
      if (width == 0 || height == 0) throw InputError("image: MJPEG frame without a readable JPEG frame header");
      if (width != im.width || height != im.height) {
        throw InputError("image: MJPEG frame is " + std::to_string(width) + "x" + std::to_string(height) +
                         " by its JPEG header, the message says " + std::to_string(im.width) + "x" +
                         std::to_string(im.height));
      }
      if (int64_t{width} * height > kMaxJpegPixels) {
        throw InputError("image: MJPEG frame of " + std::to_string(width) + "x" + std::to_string(height) +
                         " is larger than 4096x4096 pixels");
      }
      if (!ends_with_eoi(im.data)) throw InputError("image: MJPEG frame cut off (no end-of-image marker)");
      grey.create(height, width, CV_8UC1);
      JpegDecoder decoder;
      switch (decode_jpeg_grey(&decoder, im.data.data(), im.data.size(), grey.data, grey.step[0], width, height)) {
        case JpegResult::kOk: return grey;
        case JpegResult::kError: throw InputError(std::string("image: MJPEG frame does not decode: ") + decoder.error);
        case JpegResult::kWarning:
          throw InputError(std::string("image: MJPEG frame is damaged (") + decoder.warning + ")");
        case JpegResult::kWrongSize: throw InputError("image: MJPEG frame decodes to another size than its header's");
      }
      throw InputError("image: MJPEG frame does not decode");
    }
    default:
      throw InputError("image: unsupported pixel format '" + fourcc_text(im.pixelformat) + "'");
  }
}

}  // namespace

VisualTemplate make_visual_template_from_grey(const float* grey, int width, int height, int stride_floats,
                                              const VisualParams& p) {
  const int x0 = std::min(p.crop_x, width);
  const int y0 = std::min(p.crop_y, height);
  const int cw = p.crop_width == 0 ? width - x0 : std::min(p.crop_width, width - x0);
  const int ch = p.crop_height == 0 ? height - y0 : std::min(p.crop_height, height - y0);
  if (cw <= 0 || ch <= 0) {
    throw InputError("image: crop (" + std::to_string(p.crop_x) + ", " + std::to_string(p.crop_y) +
                     ") lies outside the " + std::to_string(width) + "x" + std::to_string(height) + " image");
  }
  const cv::Mat src(height, width, CV_32FC1, const_cast<float*>(grey), static_cast<size_t>(stride_floats) * 4);
  cv::Mat small;
  cv::resize(src(cv::Rect(x0, y0, cw, ch)), small, cv::Size(p.template_width, p.template_height), 0, 0,
             cv::INTER_AREA);

  const int n = p.template_width * p.template_height;
  std::vector<float> v(small.begin<float>(), small.end<float>());
  if (p.global_normalisation > 0.0) {
    double sum = 0.0;
    for (float x : v) sum += x;
    const double mean = sum / n;
    if (mean > 1e-6) {
      const float k = static_cast<float>(p.global_normalisation / mean);
      for (float& x : v) x = std::clamp(x * k, 0.0f, 1.0f);
    }
  }
  if (p.patch_radius > 0) {
    // Local contrast: removes illumination gradients the global factor cannot.
    std::vector<float> out(v.size());
    const int r = p.patch_radius;
    for (int y = 0; y < p.template_height; ++y) {
      for (int x = 0; x < p.template_width; ++x) {
        double s = 0.0, s2 = 0.0;
        int cnt = 0;
        for (int yy = std::max(0, y - r); yy <= std::min(p.template_height - 1, y + r); ++yy) {
          for (int xx = std::max(0, x - r); xx <= std::min(p.template_width - 1, x + r); ++xx) {
            const double q = v[static_cast<size_t>(yy * p.template_width + xx)];
            s += q;
            s2 += q * q;
            ++cnt;
          }
        }
        const double m = s / cnt;
        const double sd = std::sqrt(std::max(0.0, s2 / cnt - m * m));
        const double z = sd > 1e-6 ? (v[static_cast<size_t>(y * p.template_width + x)] - m) / sd : 0.0;
        out[static_cast<size_t>(y * p.template_width + x)] = static_cast<float>(std::clamp(0.5 + z / 6.0, 0.0, 1.0));
      }
    }
    v.swap(out);
  }

  VisualTemplate t;
  t.width = p.template_width;
  t.height = p.template_height;
  t.pixels.resize(static_cast<size_t>(n));
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    const auto q = static_cast<uint8_t>(std::lround(std::clamp(v[static_cast<size_t>(i)], 0.0f, 1.0f) * 255.0f));
    t.pixels[static_cast<size_t>(i)] = q;
    sum += q;
  }
  t.mean = static_cast<float>(sum / n / 255.0);
  return t;
}

VisualTemplate make_visual_template(const ImageView& image, const VisualParams& params) {
  const cv::Mat grey8 = to_grey8(image);
  cv::Mat grey;
  grey8.convertTo(grey, CV_32F, 1.0 / 255.0);
  return make_visual_template_from_grey(grey.ptr<float>(), grey.cols, grey.rows, static_cast<int>(grey.step1()),
                                        params);
}

}  // namespace whiskeye::slam
