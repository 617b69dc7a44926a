// The simulated world of vita-sim: a planar arena with heights (2.5-D). Walls and wall-mounted
// visual landmarks are vertical rectangles over floor segments; tactile landmarks are extruded 2-D
// shapes (polygons or circles with a height range) within whisker reach; surfaces carry procedural
// grey-level patterns; lighting has a base brightness and timed sudden changes; the trajectory is a
// revolution around a centre; optional sensor faults say which sensors fail when. Loaded strictly
// from YAML (config/worlds/*.yaml, format in docs/simulator.md). Pure data + geometry: no I/O
// besides the loader, no clocks.
#pragma once

#include "whiskeye/common/params.h"
#include "whiskeye/common/se2.h"
#include "whiskeye/common/whisker_array.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace whiskeye::sim {

struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

// A procedural grey-level texture over surface coordinates (s along the surface, z height), values
// 0..1 before lighting.
struct Pattern {
  enum class Type { Solid, Stripes, Checker, Blobs };
  std::string name;
  Type type = Type::Solid;
  double low = 0.2;        // dark value
  double high = 0.8;       // light value (Solid uses high)
  double period = 0.2;     // m, Stripes: one dark + one light band
  double duty = 0.5;       // Stripes: dark fraction of a period
  bool vertical = true;    // Stripes: vertical bands (vary along s) or horizontal (vary along z)
  double cell = 0.15;      // m, Checker cell size
  // Blobs: `count` dark discs on a light ground in a square tile of side `period`, repeated;
  // positions drawn from `seed` at load.
  int count = 8;
  double radius = 0.08;    // m
  uint64_t seed = 1;
  std::vector<Point2> blob_centres;  // (s, z) within the tile

  // Value at surface coordinates (s, z), 0..1.
  double value(double s, double z) const;
  // True when value() does not depend on z (solid, vertical stripes): one value per image column.
  bool constant_in_z() const { return type == Type::Solid || (type == Type::Stripes && vertical); }
};

// floor() without a library call (the default x86-64 target has no SSE4.1 round instruction).
inline double fast_floor(double x) {
  const double t = static_cast<double>(static_cast<int64_t>(x));
  return t > x ? t - 1.0 : t;
}

// a mod m in [0, m): in the renderer's per-pixel path, so no fmod.
inline double positive_mod(double a, double m) {
  const double r = a - m * fast_floor(a / m);
  return r < m ? r : 0.0;
}

// Inline: evaluated for every textured pixel.
inline double Pattern::value(double s, double z) const {
  switch (type) {
    case Type::Solid:
      return high;
    case Type::Stripes: {
      const double u = positive_mod(vertical ? s : z, period) / period;
      return u < duty ? low : high;
    }
    case Type::Checker: {
      const auto i = static_cast<int64_t>(fast_floor(s / cell)) + static_cast<int64_t>(fast_floor(z / cell));
      return (i & 1) ? high : low;
    }
    case Type::Blobs: {
      const double ts = positive_mod(s, period);
      const double tz = positive_mod(z, period);
      const double r2 = radius * radius;
      for (const Point2& c : blob_centres) {
        double ds = std::abs(ts - c.x);
        double dz = std::abs(tz - c.y);
        ds = std::min(ds, period - ds);  // the tile repeats
        dz = std::min(dz, period - dz);
        if (ds * ds + dz * dz < r2) return low;
      }
      return high;
    }
  }
  return high;
}

// A vertical rectangle over the floor segment from -> to, z in [z0, z1] (walls and wall landmarks).
struct Panel {
  std::string name;
  Point2 from;
  Point2 to;
  double z0 = 0.0;
  double z1 = 1.0;
  int pattern = 0;  // index into World::patterns
};

// An extruded 2-D shape standing on (or above) the floor: a tactile landmark.
struct Solid {
  enum class Shape { Polygon, Circle };
  std::string name;
  Shape shape = Shape::Polygon;
  std::vector<Point2> vertices;  // world frame, counter-clockwise (Polygon)
  Point2 centre;                 // world frame (Circle; bounding centre for polygons)
  double radius = 0.05;          // m (Circle; bounding radius for polygons)
  double z0 = 0.0;
  double z1 = 0.3;
  int pattern = 0;               // side faces
  double top_value = 0.6;        // grey level of the top face
  double stiffness = 1.0;        // scales the whisker deflection (soft < 1)
  // Perimeter arc length at each vertex (filled by finalize(); ray_solid computes it if empty).
  std::vector<double> perimeter_at;

  // Sets centre, radius (polygons: bounding circle) and perimeter_at from the vertices.
  void finalize();
};

struct LightChange {
  double start = 0.0;     // s since the simulation start
  double duration = 0.5;  // s
  double gain = 2.0;      // brightness multiplier while active
};

struct Lighting {
  double brightness = 1.0;  // multiplier on every surface value
  double ambient = 0.6;     // share of a surface's value independent of the viewing angle
  double attenuation = 0.05;  // brightness / (1 + attenuation * distance)
  std::vector<LightChange> changes;

  // Brightness multiplier at time t (s since the start).
  double gain_at(double t) const;
};

// The robot revolves around `centre` at `radius` (base origin), heading outwards or inwards, moving
// counter-clockwise (or clockwise) at `speed` tangentially: a sideways motion for the facing robot.
struct Trajectory {
  Point2 centre;
  double radius = 1.0;          // m
  double speed = 0.1;           // m/s, tangential
  double start_angle = 0.0;     // rad, polar angle of the start position around the centre
  bool outwards = true;         // heading = polar angle (outwards) or polar angle + pi (inwards)
  bool counter_clockwise = true;
  int laps = 4;                 // default number of revolutions

  // True base pose at time t (s since the start), on the undisturbed path (World::base_pose_at
  // adds the kidnaps).
  Pose2 pose_at(double t) const;
  // True body-frame velocity (vx, vy, omega), constant along the circle.
  void body_velocity(double& vx, double& vy, double& omega) const;
  double lap_time() const;
};

// The V4L2 format the simulated camera delivers, as camerad would publish it.
enum class CameraFormat {
  Yuyv,   // grey as luma, neutral chroma (default)
  Grey,   // 8-bit grey: half the bytes
  Mjpeg,  // a baseline JPEG a frame, YCbCr 4:2:2 with neutral chroma, as a UVC camera sends it
};

struct CameraNoise {
  double sigma = 2.0;     // grey levels (0..255), per-pixel Gaussian-like noise, 1 sigma
  CameraFormat format = CameraFormat::Yuyv;
  int jpeg_quality = 85;  // MJPEG only: libjpeg's quality, 1..100
};

struct OdometryNoise {
  double sigma_v = 0.005;       // m/s, white noise on vx and vy per 50 Hz sample
  double sigma_omega = 0.003;   // rad/s, white noise on omega
  double bias_vx = 0.0;         // m/s
  double bias_vy = 0.002;       // m/s
  double bias_omega = 0.002;    // rad/s
  double scale_v = 1.0;         // multiplies the true linear speeds (wheel radius error)
  bool start_at_truth = false;  // odometry frame = world frame (else it starts at the origin)
};

// Sensor faults the simulator injects (docs/simulator.md, "Sensor faults"). Times in s since the
// simulation start; an interval is active in [start, start + duration).
struct FaultInterval {
  double start = 0.0;
  double duration = 1.0;
};

// The whisker boards as docs/can-protocol.md wires them: board b carries whiskers 4b..4b+3
// (kNumBoards, kWhiskersPerBoard: common/whisker_array.h).

struct BoardOffline : FaultInterval {
  int board = 0;  // 0..5: whiskers 4·board .. 4·board + 3
};

struct OdometrySlip : FaultInterval {
  double scale = 1.0;  // multiplies the measured linear body velocities (vx, vy), not omega
};

// The robot lifted and put down on its own path at polar angle `to_angle`, facing as it would there;
// it goes on along its circle from there. Odometry does not see it: the body velocity is the same
// everywhere on the circle. An instant: it happens at the first control period at or after `at`.
struct Kidnap {
  double at = 0.0;        // s since the start, > 0
  double to_angle = 0.0;  // rad, polar angle around the trajectory's centre
};

struct Faults {
  std::vector<int> dead_whiskers;  // whisker indices, dead for the whole run
  std::vector<BoardOffline> board_offline;
  std::vector<FaultInterval> camera_blackout;  // no CAMERA frames
  std::vector<FaultInterval> camera_freeze;    // the last frame before the interval, repeated
  std::vector<OdometrySlip> odometry_slip;
  std::vector<Kidnap> kidnap;                  // in time order, at distinct times
};

// The most revolutions a run may have, from the world file or vita-sim's --laps; vita-sim's
// --duration is bounded by as many laps of the world's trajectory.
inline constexpr int kMaxLaps = 10000;

struct World {
  std::string name = "world";
  std::vector<Pattern> patterns;
  std::vector<Panel> walls;
  std::vector<Panel> landmarks;   // wall-mounted visual landmarks, drawn in front of the walls
  std::vector<Solid> solids;      // tactile landmarks
  double floor_value = 0.3;
  double sky_value = 0.85;        // above the walls (an open arena seen from inside)
  Lighting lighting;
  Trajectory trajectory;
  CameraNoise camera;
  OdometryNoise odometry;
  Faults faults;

  int pattern_index(const std::string& name) const;  // -1 if absent
  // True base pose at time t (s since the start): the trajectory, moved by the last kidnap at or
  // before t (compared in whole microseconds, as the simulator's control periods are).
  Pose2 base_pose_at(double t) const;
};

// Loads `world:` from a parsed document; strict (unknown keys, unknown pattern names, degenerate
// shapes are ParamErrors naming the key).
void load(const ParamNode& node, World& world);
// The `world:` document of a parsed world file (or text), checked for unknown keys: what every
// reader of a whole world file calls.
World load_world(const ParamNode& root);
// Reads a world file: load_world(ParamNode::from_file(path)).
World load_world_file(const std::string& path);

// ---- 2-D ray geometry shared by the renderer and the whisker contact model ----

// Where a horizontal ray (origin o, unit direction d) crosses a panel: distance t >= 0 and the
// surface coordinate s (m from `from`). False if it misses.
bool ray_panel(const Point2& o, const Point2& d, const Panel& p, double& t, double& s);

// One passage of a horizontal ray through a solid's footprint.
struct SolidHit {
  double t_in = 0.0;    // distance at entry (< 0 when the origin is inside)
  double t_out = 0.0;   // distance at exit
  double s_in = 0.0;    // surface coordinate at entry (perimeter arc length from the first vertex)
  double cos_in = 1.0;  // |cos| of the angle between the ray and the surface normal at entry
};

// Every passage of a horizontal ray (origin o, unit direction d) through a solid's footprint that
// ends ahead of the origin (t_out >= 0), nearest first. Appends to `out`; returns how many.
int ray_solid(const Point2& o, const Point2& d, const Solid& solid, std::vector<SolidHit>& out);

}  // namespace whiskeye::sim
