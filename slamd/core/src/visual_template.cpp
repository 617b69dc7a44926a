// Visual template: every pixel format ends as a float greyscale image in [0, 1], which is cropped,
// block-averaged (OpenCV INTER_AREA = exact area averaging, also for non-integer ratios) and
// normalised. See visual_template.h.
#include "whiskeye/slam/visual_template.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

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

// The part of a width × height image that `p` crops; throws when nothing is left.
cv::Rect crop_rect(const VisualParams& p, int width, int height) {
  const int x0 = std::min(p.crop_x, width);
  const int y0 = std::min(p.crop_y, height);
  const int cw = p.crop_width == 0 ? width - x0 : std::min(p.crop_width, width - x0);
  const int ch = p.crop_height == 0 ? height - y0 : std::min(p.crop_height, height - y0);
  if (cw <= 0 || ch <= 0) {
    throw InputError("image: crop (" + std::to_string(p.crop_x) + ", " + std::to_string(p.crop_y) +
                     ") lies outside the " + std::to_string(width) + "x" + std::to_string(height) + " image");
  }
  return {x0, y0, cw, ch};
}

// 8-bit grey to [0, 1] exactly as cv::Mat::convertTo(CV_32F, 1.0 / 255) computes it: the byte as a
// float times the scale as a float (OpenCV's cvt_32f; its b term is 0).
const std::array<float, 256>& unit_grey() {
  static const std::array<float, 256> lut = [] {
    std::array<float, 256> l{};
    const auto scale = static_cast<float>(1.0 / 255.0);
    for (int v = 0; v < 256; ++v) l[static_cast<size_t>(v)] = static_cast<float>(v) * scale;
    return l;
  }();
  return lut;
}

// The crop of `im` as a float grey image in [0, 1]. Only the crop is converted: every format's grey
// value of a pixel depends on that pixel alone (YUYV: its Y byte; RGB/BGR: OpenCV's fixed-point
// weights), so this equals converting the whole image and cropping it, which it did until
// 2026-12-04 (docs/performance.md, "### Replay").
cv::Mat crop_to_unit_grey(const ImageView& im, const VisualParams& p, const FrameDecoder* decoder) {
  // OpenCV wants a non-const pointer for a header over foreign data; it is only read.
  auto* data = const_cast<uint8_t*>(im.data.data());
  const auto stride = static_cast<size_t>(im.row_stride);
  cv::Rect c;
  const uint8_t* bytes = nullptr;  // the crop's first grey byte
  size_t step = 0;                 // between two grey bytes of a row
  size_t row_step = 0;             // between two rows
  cv::Mat grey8;
  switch (im.pixelformat) {
    case kPixGrey:
      check_raw(im, 1);
      c = crop_rect(p, im.width, im.height);
      bytes = data + static_cast<size_t>(c.y) * stride + static_cast<size_t>(c.x);
      step = 1;
      row_step = stride;
      break;
    case kPixYuyv:
      check_raw(im, 2);
      c = crop_rect(p, im.width, im.height);
      bytes = data + static_cast<size_t>(c.y) * stride + 2 * static_cast<size_t>(c.x);  // Y, U, Y, V: Y every other byte
      step = 2;
      row_step = stride;
      break;
    case kPixRgb24:
    case kPixBgr24:
      check_raw(im, 3);
      c = crop_rect(p, im.width, im.height);
      cv::cvtColor(cv::Mat(im.height, im.width, CV_8UC3, data, stride)(c), grey8,
                   im.pixelformat == kPixRgb24 ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
      bytes = grey8.data;
      step = 1;
      row_step = grey8.step[0];
      break;
    default:
      if (decoder != nullptr && im.pixelformat == decoder->pixelformat) {
        decoder->check(im);  // before allocating what the message claims
        grey8.create(im.height, im.width, CV_8UC1);
        decoder->decode(im, grey8.data, grey8.step[0]);
        c = crop_rect(p, im.width, im.height);
        bytes = grey8.ptr(c.y) + c.x;
        step = 1;
        row_step = grey8.step[0];
        break;
      }
      throw InputError("image: unsupported pixel format '" + fourcc_text(im.pixelformat) + "'");
  }
  const std::array<float, 256>& unit = unit_grey();
  cv::Mat out(c.height, c.width, CV_32FC1);
  for (int y = 0; y < c.height; ++y) {
    const uint8_t* in = bytes + static_cast<size_t>(y) * row_step;
    auto* o = out.ptr<float>(y);
    for (int x = 0; x < c.width; ++x) o[x] = unit[in[static_cast<size_t>(x) * step]];
  }
  return out;
}

}  // namespace

VisualTemplate make_visual_template_from_grey(const float* grey, int width, int height, int stride_floats,
                                              const VisualParams& p) {
  const cv::Rect crop = crop_rect(p, width, height);
  const cv::Mat src(height, width, CV_32FC1, const_cast<float*>(grey), static_cast<size_t>(stride_floats) * 4);
  cv::Mat small;
  cv::resize(src(crop), small, cv::Size(p.template_width, p.template_height), 0, 0, cv::INTER_AREA);

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

VisualTemplate make_visual_template(const ImageView& image, const VisualParams& params, const FrameDecoder* decoder) {
  const cv::Mat grey = crop_to_unit_grey(image, params, decoder);
  VisualParams whole = params;  // the crop is all there is now
  whole.crop_x = whole.crop_y = whole.crop_width = whole.crop_height = 0;
  return make_visual_template_from_grey(grey.ptr<float>(), grey.cols, grey.rows, static_cast<int>(grey.step1()),
                                        whole);
}

}  // namespace whiskeye::slam
