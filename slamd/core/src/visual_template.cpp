// Visual template: every pixel format ends as grey in [0, 1], which is cropped, area-averaged
// (OpenCV INTER_AREA's arithmetic, also for non-integer ratios) and normalised. See
// visual_template.h.
#include "whiskeye/slam/visual_template.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

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

// Bytes per pixel of the uncompressed formats the core reads; 0 for any other.
int raw_bytes_per_pixel(uint32_t fourcc) {
  switch (fourcc) {
    case kPixGrey:
      return 1;
    case kPixYuyv:
      return 2;
    case kPixRgb24:
    case kPixBgr24:
      return 3;
    default:
      return 0;
  }
}

// Why an uncompressed image's size, row stride and data do not fit together, or "".
std::string raw_size_error(const ImageView& im) {
  const int bytes_per_pixel = raw_bytes_per_pixel(im.pixelformat);
  if (im.width <= 0 || im.height <= 0) return "image: bad size " + std::to_string(im.width) + "x" + std::to_string(im.height);
  const int64_t row_bytes = static_cast<int64_t>(im.width) * bytes_per_pixel;
  if (im.row_stride < row_bytes) {
    return "image: row_stride " + std::to_string(im.row_stride) + " < " + std::to_string(row_bytes) + " bytes for " +
           fourcc_text(im.pixelformat) + " width " + std::to_string(im.width);
  }
  const int64_t need = static_cast<int64_t>(im.row_stride) * (im.height - 1) + row_bytes;
  if (static_cast<int64_t>(im.data.size()) < need) {
    return "image: " + std::to_string(im.data.size()) + " bytes of data, " + std::to_string(need) + " needed for " +
           std::to_string(im.width) + "x" + std::to_string(im.height) + " " + fourcc_text(im.pixelformat);
  }
  return "";
}

void check_raw(const ImageView& im) {
  if (std::string bad = raw_size_error(im); !bad.empty()) throw InputError(bad);
}

// The part of a width × height image that `p` crops, or none when nothing is left.
std::optional<cv::Rect> fitted_crop(const VisualParams& p, int width, int height) {
  const int x0 = std::min(p.crop_x, width);
  const int y0 = std::min(p.crop_y, height);
  const int cw = p.crop_width == 0 ? width - x0 : std::min(p.crop_width, width - x0);
  const int ch = p.crop_height == 0 ? height - y0 : std::min(p.crop_height, height - y0);
  if (cw <= 0 || ch <= 0) return std::nullopt;
  return cv::Rect{x0, y0, cw, ch};
}

// The same; throws when nothing is left.
cv::Rect crop_rect(const VisualParams& p, int width, int height) {
  if (const std::optional<cv::Rect> crop = fitted_crop(p, width, height)) return *crop;
  throw InputError("image: crop (" + std::to_string(p.crop_x) + ", " + std::to_string(p.crop_y) +
                   ") lies outside the " + std::to_string(width) + "x" + std::to_string(height) + " image");
}

// The crop of an image as 8-bit grey bytes: `bytes` is the crop's first grey byte, `step` the
// distance between two grey bytes of a row, `row_step` between two rows. `storage` holds the
// converted image when the format needs one (RGB, BGR, a decoded frame).
struct GreyCrop {
  cv::Rect rect;
  const uint8_t* bytes = nullptr;
  size_t step = 0;
  size_t row_step = 0;
  cv::Mat storage;
};

// Only the crop is converted: every format's grey value of a pixel depends on that pixel alone
// (YUYV: its Y byte; RGB/BGR: OpenCV's fixed-point weights), so this equals converting the whole
// image and cropping it.
GreyCrop grey_crop(const ImageView& im, const VisualParams& p, const FrameDecoder* decoder) {
  // OpenCV wants a non-const pointer for a header over foreign data; it is only read.
  auto* data = const_cast<uint8_t*>(im.data.data());
  const auto stride = static_cast<size_t>(im.row_stride);
  GreyCrop g;
  switch (im.pixelformat) {
    case kPixGrey:
      check_raw(im);
      g.rect = crop_rect(p, im.width, im.height);
      g.bytes = data + static_cast<size_t>(g.rect.y) * stride + static_cast<size_t>(g.rect.x);
      g.step = 1;
      g.row_step = stride;
      return g;
    case kPixYuyv:
      check_raw(im);
      g.rect = crop_rect(p, im.width, im.height);
      g.bytes = data + static_cast<size_t>(g.rect.y) * stride + 2 * static_cast<size_t>(g.rect.x);  // Y, U, Y, V
      g.step = 2;
      g.row_step = stride;
      return g;
    case kPixRgb24:
    case kPixBgr24:
      check_raw(im);
      g.rect = crop_rect(p, im.width, im.height);
      cv::cvtColor(cv::Mat(im.height, im.width, CV_8UC3, data, stride)(g.rect), g.storage,
                   im.pixelformat == kPixRgb24 ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
      g.bytes = g.storage.data;
      g.step = 1;
      g.row_step = g.storage.step[0];
      return g;
    default:
      if (decoder != nullptr && im.pixelformat == decoder->pixelformat) {
        decoder->check(im);  // before allocating what the message claims
        g.storage.create(im.height, im.width, CV_8UC1);
        decoder->decode(im, g.storage.data, g.storage.step[0]);
        g.rect = crop_rect(p, im.width, im.height);
        g.bytes = g.storage.ptr(g.rect.y) + g.rect.x;
        g.step = 1;
        g.row_step = g.storage.step[0];
        return g;
      }
      throw InputError("image: unsupported pixel format '" + fourcc_text(im.pixelformat) + "'");
  }
}

// One axis of an area average from `from` cells to `to`: for each destination cell, the source
// cells it overlaps, in order, each with its share of the cell (overlap / cell width, as a float).
// These are OpenCV's INTER_AREA weights for a shrink by a non-integer factor, computed the same
// way (the scale as 1 / (to / from) in double, a part overlap under 1e-3 dropped), so that
// `area_average` gives cv::resize's floats bit for bit.
struct AreaAxis {
  std::vector<int> begin;  // destination cell d's taps are [begin[d], begin[d + 1])
  std::vector<int> source;
  std::vector<float> share;
  int whole = 0;  // > 0: every cell d is the `whole` source cells from d·whole on, with one share
};

AreaAxis area_axis(int from, int to) {
  const double scale = 1.0 / (static_cast<double>(to) / from);
  AreaAxis a;
  a.begin.reserve(static_cast<size_t>(to) + 1);
  auto tap = [&a](int s, double w) {
    a.source.push_back(s);
    a.share.push_back(static_cast<float>(w));
  };
  for (int d = 0; d < to; ++d) {
    a.begin.push_back(static_cast<int>(a.source.size()));
    const double lo = d * scale, hi = lo + scale;
    const double width = std::min(scale, from - lo);
    int last = std::min(static_cast<int>(std::floor(hi)), from - 1);
    const int first = std::min(static_cast<int>(std::ceil(lo)), last);
    if (first - lo > 1e-3) tap(first - 1, (first - lo) / width);
    for (int s = first; s < last; ++s) tap(s, 1.0 / width);
    if (hi - last > 1e-3) tap(last, std::min(std::min(hi - last, 1.0), width) / width);
  }
  a.begin.push_back(static_cast<int>(a.source.size()));
  const int r = from / to;
  if (r * to == from && static_cast<int>(a.source.size()) == from &&
      std::all_of(a.share.begin(), a.share.end(), [&a](float w) { return w == a.share.front(); })) {
    a.whole = r;  // then source[k] == k: cell d's taps are d·r … d·r + r − 1
  }
  return a;
}

// Whether cv::resize's INTER_AREA takes the weighted path `area_average` reproduces: a shrink on
// both axes by a factor that is not a whole number on both (whole numbers take its block-sum path,
// an enlargement its bilinear one).
bool weighted_area_path(int from_w, int from_h, int to_w, int to_h) {
  const double sx = 1.0 / (static_cast<double>(to_w) / from_w), sy = 1.0 / (static_cast<double>(to_h) / from_h);
  if (sx < 1.0 || sy < 1.0) return false;
  const auto whole = [](double s) { return std::abs(s - std::round(s)) < std::numeric_limits<double>::epsilon(); };
  return !(whole(sx) && whole(sy));
}

// The area average of a from_w × from_h float image into to_w × to_h (`out`, row-major), with
// cv::resize's arithmetic: each source row's horizontal sums in float, in source order, then the
// rows weighted and summed in order. `row(y, buffer)` writes source row y (from_w floats). A source
// row on the border of two destination rows is read and summed once, for both.
template <class Row>
void area_average(int from_w, int from_h, int to_w, int to_h, Row&& row, float* out) {
  const AreaAxis ax = area_axis(from_w, to_w), ay = area_axis(from_h, to_h);
  std::vector<float> buffer(static_cast<size_t>(from_w));
  std::vector<float> h(static_cast<size_t>(to_w));
  int summed = -1;  // the source row whose sums `h` holds
  for (int dy = 0; dy < to_h; ++dy) {
    float* o = out + static_cast<size_t>(dy) * static_cast<size_t>(to_w);
    for (int j = ay.begin[static_cast<size_t>(dy)]; j < ay.begin[static_cast<size_t>(dy) + 1]; ++j) {
      const int y = ay.source[static_cast<size_t>(j)];
      if (y != summed) {
        row(y, buffer.data());
        const float* in = buffer.data();
        if (ax.whole > 0) {
          // Every destination column is `whole` source columns with one share (slam.yaml's 640 → 64).
          // Tap by tap over all columns (strided loads the compiler vectorises), each column's taps in order.
          const float w = ax.share.front();
          const size_t r = static_cast<size_t>(ax.whole);
          float* hs = h.data();
          for (size_t dx = 0; dx < static_cast<size_t>(to_w); ++dx) hs[dx] = 0.0f + in[dx * r] * w;
          for (size_t k = 1; k < r; ++k) {
            for (size_t dx = 0; dx < static_cast<size_t>(to_w); ++dx) hs[dx] += in[dx * r + k] * w;
          }
        } else {
          for (int dx = 0; dx < to_w; ++dx) {
            float s = 0.0f;
            for (int k = ax.begin[static_cast<size_t>(dx)]; k < ax.begin[static_cast<size_t>(dx) + 1]; ++k) {
              s += in[ax.source[static_cast<size_t>(k)]] * ax.share[static_cast<size_t>(k)];
            }
            h[static_cast<size_t>(dx)] = s;
          }
        }
        summed = y;
      }
      const float beta = ay.share[static_cast<size_t>(j)];
      if (j == ay.begin[static_cast<size_t>(dy)]) {
        for (int dx = 0; dx < to_w; ++dx) o[dx] = beta * h[static_cast<size_t>(dx)];
      } else {
        for (int dx = 0; dx < to_w; ++dx) o[dx] += beta * h[static_cast<size_t>(dx)];
      }
    }
  }
}

// The template from its subsampled float pixels (`small`, width·height of `p`): normalised and
// quantised.
VisualTemplate finish_template(std::vector<float> v, const VisualParams& p) {
  const int n = p.template_width * p.template_height;
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

}  // namespace

ImageView visual_rows(const ImageView& image, const VisualParams& params) {
  // A compressed image, a crop that reaches the last row, a crop beyond the image (which keeps
  // every row, and so its error, with the image's own size), or sizes that do not fit: every row.
  if (raw_bytes_per_pixel(image.pixelformat) == 0) return image;
  const std::optional<cv::Rect> crop = fitted_crop(params, image.width, image.height);
  if (!crop || crop->br().y >= image.height || !raw_size_error(image).empty()) return image;
  const int bottom = crop->br().y;
  ImageView part = image;
  part.height = bottom;
  part.data = image.data.first(std::min(image.data.size(), static_cast<size_t>(bottom) * static_cast<size_t>(image.row_stride)));
  return part;
}

void area_shrink(const float* grey, int width, int height, int stride_floats, float* out, int out_width,
                 int out_height) {
  if (weighted_area_path(width, height, out_width, out_height)) {
    area_average(
        width, height, out_width, out_height,
        [&](int y, float* buffer) {
          const float* in = grey + static_cast<size_t>(y) * static_cast<size_t>(stride_floats);
          std::copy_n(in, width, buffer);
        },
        out);
    return;
  }
  const cv::Mat src(height, width, CV_32FC1, const_cast<float*>(grey), static_cast<size_t>(stride_floats) * 4);
  cv::Mat dst(out_height, out_width, CV_32FC1, out);
  cv::resize(src, dst, dst.size(), 0, 0, cv::INTER_AREA);
}

VisualTemplate make_visual_template_from_grey(const float* grey, int width, int height, int stride_floats,
                                              const VisualParams& p) {
  const cv::Rect crop = crop_rect(p, width, height);
  std::vector<float> small(static_cast<size_t>(p.template_width) * static_cast<size_t>(p.template_height));
  area_shrink(grey + static_cast<size_t>(crop.y) * static_cast<size_t>(stride_floats) + static_cast<size_t>(crop.x),
              crop.width, crop.height, stride_floats, small.data(), p.template_width, p.template_height);
  return finish_template(std::move(small), p);
}

VisualTemplate make_visual_template(const ImageView& image, const VisualParams& params, const FrameDecoder* decoder) {
  const GreyCrop g = grey_crop(image, params, decoder);
  const int w = g.rect.width, h = g.rect.height;
  // Row y of the crop as floats in [0, 1], the byte as a float times 1/255 as a float, exactly as
  // cv::Mat::convertTo(CV_32F, 1.0 / 255) computes it (OpenCV's cvt_32f; its b term is 0). One loop
  // per grey step (grey, YUYV) so that each vectorises.
  const auto scale = static_cast<float>(1.0 / 255.0);
  const auto grey_row = [&g, w, scale](int y, float* out) {
    const uint8_t* in = g.bytes + static_cast<size_t>(y) * g.row_step;
    if (g.step == 1) {
      for (int x = 0; x < w; ++x) out[x] = static_cast<float>(in[x]) * scale;
    } else if (g.step == 2) {
      for (int x = 0; x < w; ++x) out[x] = static_cast<float>(in[2 * static_cast<size_t>(x)]) * scale;
    } else {
      for (int x = 0; x < w; ++x) out[x] = static_cast<float>(in[static_cast<size_t>(x) * g.step]) * scale;
    }
  };
  std::vector<float> small(static_cast<size_t>(params.template_width) * static_cast<size_t>(params.template_height));
  if (weighted_area_path(w, h, params.template_width, params.template_height)) {
    // Row by row: only the rows the average reads are converted, straight into its buffer.
    area_average(w, h, params.template_width, params.template_height, grey_row, small.data());
  } else {
    std::vector<float> grey(static_cast<size_t>(w) * static_cast<size_t>(h));
    for (int y = 0; y < h; ++y) grey_row(y, &grey[static_cast<size_t>(y) * static_cast<size_t>(w)]);
    area_shrink(grey.data(), w, h, w, small.data(), params.template_width, params.template_height);
  }
  return finish_template(std::move(small), params);
}

}  // namespace whiskeye::slam
