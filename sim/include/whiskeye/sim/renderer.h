// Camera renderer of vita-sim: one horizontal ray per image column against the world's walls,
// wall landmarks and tactile solids (the world is 2-D with heights), then each column's pixels are
// filled front to back from the surfaces' height ranges, with procedural textures, viewing-angle
// shading, distance attenuation, the lighting's brightness at time t and per-pixel noise. A pinhole
// camera at the head's camera position looking along head x, image centre at the middle.
// Fast enough for ≥ 50× real time at 5 fps; deterministic for a given noise state.
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/sim/world.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace whiskeye::sim {

// xorshift64*: small, fully specified, fast; used for per-pixel noise.
class FastRng {
 public:
  explicit FastRng(uint64_t seed) : state_(seed * 0x9E3779B97F4A7C15ull + 0x2545F4914F6CDD1Dull) {
    if (state_ == 0) state_ = 1;
  }
  uint64_t next() {
    state_ ^= state_ >> 12;
    state_ ^= state_ << 25;
    state_ ^= state_ >> 27;
    return state_ * 0x2545F4914F6CDD1Dull;
  }

 private:
  uint64_t state_;
};

class Renderer {
 public:
  Renderer(const World& world, const RobotGeometry& robot);

  int width() const { return width_; }
  int height() const { return height_; }
  double focal_length() const { return f_; }  // pixels

  // Renders the 8-bit grey image (row-major, width × height) seen from the true base pose at time t
  // (s since the start; for the lighting). Noise (world.camera.sigma) is drawn from `rng`.
  void render(const Pose2& T_world_base, double t, FastRng& rng, std::vector<uint8_t>& grey);

  // Bearing (rad, ccw from the optical axis) of the centre of image column u.
  double column_bearing(int u) const;
  // The column (fractional, pixel centres at u + 0.5) where a bearing projects.
  double bearing_column(double bearing) const;

 private:
  struct Hit {
    double t;       // horizontal distance from the camera
    double t_out;   // solids: exit distance (top faces); = t for panels
    double s;       // surface coordinate
    double shade;   // viewing-angle × distance factor
    double z0;
    double z1;
    const Pattern* pattern;
    double top_value;  // solids only; < 0 for panels
  };
  // A wall or landmark with what every ray needs precomputed.
  struct FlatPanel {
    Point2 from;
    double ex;
    double ey;
    double length;
    double z0;
    double z1;
    double bias;  // subtracted from the distance for the depth order
    const Pattern* pattern;
  };
  // Writes the column's intensities (0..1, before lighting and noise) to out[v * stride].
  void render_column(const Point2& cam, double heading, int u, float* out, std::size_t stride);

  const World& world_;
  int width_;
  int height_;
  double f_;
  double cam_z_;
  Vec3 p_camera_in_head_;
  Pose2 T_base_head_;
  std::vector<FlatPanel> panels_;
  std::vector<Hit> hits_;
  std::vector<std::pair<int, int>> painted_;  // rows already painted in this column (sorted intervals)
  std::vector<SolidHit> solid_hits_;
  static constexpr int kStrip = 16;  // columns rendered before they are copied into the image
  std::vector<float> strip_;    // kStrip columns of them, row-major (row v: strip_[v * kStrip + j])
  std::vector<float> noise_;    // 256 quantiles of N(0, sigma²), grey levels: noise by table look-up
};

// Packs 8-bit grey into V4L2 YUYV (Y0 U Y1 V, neutral chroma 128). Width must be even.
void grey_to_yuyv(const std::vector<uint8_t>& grey, int width, int height, std::vector<uint8_t>& yuyv);

}  // namespace whiskeye::sim
