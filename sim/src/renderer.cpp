// Column ray-casting renderer (see renderer.h).
#include "whiskeye/sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace whiskeye::sim {

namespace {

// Landmarks are mounted on walls (same distance): they must win the depth order.
constexpr double kLandmarkBias = 1e-4;

// Φ⁻¹(p) by Newton's method on the normal CDF (table set-up only).
double normal_quantile(double p) {
  double x = 0.0;
  for (int i = 0; i < 60; ++i) {
    const double cdf = 0.5 * std::erfc(-x / std::sqrt(2.0));
    const double pdf = std::exp(-0.5 * x * x) / std::sqrt(2.0 * kPi);
    const double step = (cdf - p) / std::max(pdf, 1e-300);
    x -= std::clamp(step, -1.0, 1.0);
    if (std::abs(step) < 1e-12) break;
  }
  return x;
}

}  // namespace

Renderer::Renderer(const World& world, const RobotGeometry& robot)
    : world_(world),
      width_(robot.camera.width),
      height_(robot.camera.height),
      f_(0.5 * robot.camera.width / std::tan(0.5 * robot.camera.hfov)),
      cam_z_(robot.head_height + robot.camera.p_camera_in_head.z),
      p_camera_in_head_(robot.camera.p_camera_in_head),
      T_base_head_(robot.T_base_head) {
  if (width_ % 2 != 0) throw std::invalid_argument("camera width must be even (YUYV pairs)");
  strip_.resize(static_cast<std::size_t>(kStrip) * static_cast<std::size_t>(height_));
  // 8 random bits per pixel pick one of 256 quantiles of the Gaussian: its marginal distribution
  // (up to ±2.9 σ) at the cost of a 1 KB table look-up.
  noise_.resize(256);
  for (std::size_t k = 0; k < noise_.size(); ++k) {
    noise_[k] = static_cast<float>(world_.camera.sigma * normal_quantile((static_cast<double>(k) + 0.5) / 256.0));
  }

  auto add = [&](const std::vector<Panel>& panels, double bias) {
    for (const Panel& p : panels) {
      const double ex = p.to.x - p.from.x;
      const double ey = p.to.y - p.from.y;
      panels_.push_back({p.from, ex, ey, std::hypot(ex, ey), p.z0, p.z1, bias,
                         &world_.patterns.at(static_cast<std::size_t>(p.pattern))});
    }
  };
  add(world_.walls, 0.0);
  add(world_.landmarks, kLandmarkBias);
}

double Renderer::column_bearing(int u) const { return std::atan((0.5 * width_ - (u + 0.5)) / f_); }

double Renderer::bearing_column(double bearing) const { return 0.5 * width_ - f_ * std::tan(bearing); }

void Renderer::render_column(const Point2& cam, double heading, int u, float* out, std::size_t stride) {
  const double a = (0.5 * width_ - (u + 0.5)) / f_;
  const double k = std::sqrt(1.0 + a * a);  // horizontal ray distance per unit of forward depth
  const double bearing = heading + std::atan(a);
  const Point2 d{std::cos(bearing), std::sin(bearing)};
  const Lighting& light = world_.lighting;

  hits_.clear();
  for (const FlatPanel& p : panels_) {
    const double den = d.x * p.ey - d.y * p.ex;  // cross(d, e)
    if (std::abs(den) < 1e-12) continue;
    const double wx = p.from.x - cam.x;
    const double wy = p.from.y - cam.y;
    const double t = (wx * p.ey - wy * p.ex) / den;
    const double u01 = (wx * d.y - wy * d.x) / den;
    if (t < 1e-6 || u01 < 0.0 || u01 > 1.0) continue;
    const double cos_in = std::abs(den) / p.length;
    const double shade = (light.ambient + (1.0 - light.ambient) * cos_in) / (1.0 + light.attenuation * t);
    hits_.push_back({t - p.bias, t, u01 * p.length, shade, p.z0, p.z1, p.pattern, -1.0});
  }
  for (const Solid& solid : world_.solids) {
    solid_hits_.clear();
    ray_solid(cam, d, solid, solid_hits_);
    for (const SolidHit& h : solid_hits_) {
      if (h.t_in < 1e-6) continue;  // the camera inside a solid sees nothing of it
      const double shade = (light.ambient + (1.0 - light.ambient) * h.cos_in) / (1.0 + light.attenuation * h.t_in);
      hits_.push_back({h.t_in, h.t_out, h.s_in, shade, solid.z0, solid.z1,
                       &world_.patterns[static_cast<std::size_t>(solid.pattern)], solid.top_value});
    }
  }
  std::sort(hits_.begin(), hits_.end(), [](const Hit& p, const Hit& q) { return p.t < q.t; });

  const double cy = 0.5 * height_;
  const double fk = f_ * k;
  auto row_of = [&](double z, double t) { return cy + (cam_z_ - z) * fk / t - 0.5; };  // fractional row
  auto clamp_row = [&](double v) {
    return static_cast<int>(std::clamp(v, -1.0, static_cast<double>(height_)));
  };
  // Surfaces are painted front to back; each covers one interval of rows, so the painted rows are a
  // few sorted intervals and every pixel is written exactly once.
  painted_.clear();
  auto paint = [&](int a, int b, auto&& fill) {
    a = std::max(a, 0);
    b = std::min(b, height_ - 1);
    if (a > b) return;
    int cur = a;
    for (const auto& [p0, p1] : painted_) {
      if (p1 < cur) continue;
      if (p0 > b) break;
      if (p0 > cur) fill(cur, std::min(b, p0 - 1));
      cur = std::max(cur, p1 + 1);
      if (cur > b) break;
    }
    if (cur <= b) fill(cur, b);
    // Insert [a, b] and merge overlapping or touching intervals.
    auto it = std::lower_bound(painted_.begin(), painted_.end(), std::pair{a, b});
    it = painted_.insert(it, {a, b});
    std::size_t w = 0;
    for (std::size_t r = 1; r < painted_.size(); ++r) {
      if (painted_[r].first <= painted_[w].second + 1) {
        painted_[w].second = std::max(painted_[w].second, painted_[r].second);
      } else {
        painted_[++w] = painted_[r];
      }
    }
    painted_.resize(w + 1);
  };
  for (const Hit& h : hits_) {
    if (painted_.size() == 1 && painted_[0].first == 0 && painted_[0].second == height_ - 1) break;
    const double t = std::max(h.t, 1e-6);
    const int v0 = clamp_row(std::ceil(row_of(h.z1, t)));
    const int v1 = clamp_row(std::floor(row_of(h.z0, t)));
    if (h.pattern->constant_in_z()) {
      const float value = static_cast<float>(h.pattern->value(h.s, 0.0) * h.shade);
      paint(v0, v1, [&](int a, int b) {
        for (int v = a; v <= b; ++v) out[static_cast<std::size_t>(v) * stride] = value;
      });
    } else {
      paint(v0, v1, [&](int a, int b) {
        for (int v = a; v <= b; ++v) {
          const double z = cam_z_ - ((v + 0.5) - cy) * t / fk;
          out[static_cast<std::size_t>(v) * stride] = static_cast<float>(h.pattern->value(h.s, z) * h.shade);
        }
      });
    }
    // The top face of a solid below the camera, seen between its entry and exit distances.
    if (h.top_value >= 0.0 && h.z1 < cam_z_ && h.t_out > t) {
      const int w0 = clamp_row(std::ceil(row_of(h.z1, h.t_out)));
      const int w1 = clamp_row(std::floor(row_of(h.z1, t)));
      const float top = static_cast<float>(h.top_value * light.ambient / (1.0 + light.attenuation * t));
      paint(w0, w1, [&](int a, int b) {
        for (int v = a; v <= b; ++v) out[static_cast<std::size_t>(v) * stride] = top;
      });
    }
  }
  // What no surface covers: the sky above the horizon, the floor below.
  const int horizon = static_cast<int>(std::ceil(cy - 0.5));  // first row whose centre is below cy
  const float sky = static_cast<float>(world_.sky_value);
  paint(0, horizon - 1, [&](int a, int b) {
    for (int v = a; v <= b; ++v) out[static_cast<std::size_t>(v) * stride] = sky;
  });
  paint(horizon, height_ - 1, [&](int a, int b) {
    for (int v = a; v <= b; ++v) {
      const double t = cam_z_ * fk / ((v + 0.5) - cy);
      out[static_cast<std::size_t>(v) * stride] =
          static_cast<float>(world_.floor_value * light.ambient / (1.0 + light.attenuation * t));
    }
  });
}

void Renderer::render(const Pose2& T_world_base, double t, FastRng& rng, std::vector<uint8_t>& grey) {
  const Pose2 head = compose(T_world_base, T_base_head_);
  Point2 cam;
  transform_point(head, p_camera_in_head_.x, p_camera_in_head_.y, cam.x, cam.y);
  // Columns are rendered a strip at a time (the strip stays in L1), then each row of the strip gets
  // lighting, noise (drawn in strip-row order: deterministic) and quantisation in one pass.
  const std::size_t H = static_cast<std::size_t>(height_);
  const std::size_t W = static_cast<std::size_t>(width_);
  const float gain = static_cast<float>(255.0 * world_.lighting.gain_at(t));
  const bool noisy = world_.camera.sigma > 0.0;
  const float* table = noise_.data();
  grey.resize(W * H);
  float* strip = strip_.data();  // row-major: strip[v * kStrip + j]
  alignas(64) float noise[kStrip] = {};
  for (int u0 = 0; u0 < width_; u0 += kStrip) {
    const int m = std::min(kStrip, width_ - u0);
    for (int j = 0; j < m; ++j) {
      render_column(cam, head.theta, u0 + j, strip + j, kStrip);
    }
    for (std::size_t v = 0; v < H; ++v) {
      if (noisy) {
        for (int j = 0; j < kStrip; j += 8) {
          uint64_t r = rng.next();  // eight pixels per draw
          for (int k = 0; k < 8; ++k, r >>= 8) noise[j + k] = table[r & 0xFF];
        }
      }
      const float* row = &strip[v * kStrip];
      uint8_t* dst = &grey[v * W + static_cast<std::size_t>(u0)];
      // Branch-free, contiguous: vectorised (this file is built with -ftree-vectorize).
      auto quantise = [&](int count) {
        for (int j = 0; j < count; ++j) {
          // Clamped as integers: float min/max does not vectorise without -ffast-math.
          const int q = static_cast<int>(row[j] * gain + noise[j] + 0.5f);
          dst[j] = static_cast<uint8_t>(std::clamp(q, 0, 255));
        }
      };
      if (m == kStrip) {
        quantise(kStrip);  // constant trip count: fully vectorised
      } else {
        quantise(m);
      }
    }
  }
}

void grey_to_yuyv(const std::vector<uint8_t>& grey, int width, int height, std::vector<uint8_t>& yuyv) {
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  yuyv.resize(2 * n);
  const uint8_t* in = grey.data();
  uint8_t* out = yuyv.data();
  for (std::size_t i = 0; i < n; ++i) {
    out[2 * i] = in[i];
    out[2 * i + 1] = 128;
  }
}

}  // namespace whiskeye::sim
