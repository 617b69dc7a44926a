// World model of vita-sim: patterns, lighting, trajectory, strict YAML loading and the 2-D ray
// geometry shared by the renderer and the whisker contact model.
#include "whiskeye/sim/world.h"

#include <algorithm>
#include <cmath>

namespace whiskeye::sim {

namespace {

// splitmix64: a tiny, fully specified generator, so blob layouts are identical on every platform.
uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double uniform01(uint64_t& state) { return static_cast<double>(splitmix64(state) >> 11) * 0x1.0p-53; }


[[noreturn]] void bad(const ParamNode& n, const std::string& key, const std::string& what) {
  throw ParamError(n.source() + ": '" + n.path_of(key) + "' " + what);
}

Point2 get_point(const ParamNode& n, const std::string& key, Point2 def, bool required = false) {
  std::vector<double> v{def.x, def.y};
  if (required) {
    n.require(key, v);
  } else {
    n.get(key, v);
  }
  if (v.size() != 2) bad(n, key, "must be a list [x, y]");
  return {v[0], v[1]};
}

void get_range(const ParamNode& n, const std::string& key, double& z0, double& z1) {
  std::vector<double> v{z0, z1};
  n.get(key, v);
  if (v.size() != 2 || !(v[0] >= 0.0 && v[1] > v[0] && v[1] <= 100.0)) {
    bad(n, key, "must be [z0, z1] with 0 <= z0 < z1 (m)");
  }
  z0 = v[0];
  z1 = v[1];
}

int get_pattern(const ParamNode& n, const World& w) {
  std::string name;
  n.require("pattern", name);
  const int i = w.pattern_index(name);
  if (i < 0) bad(n, "pattern", "names an undefined pattern '" + name + "'");
  return i;
}

Panel load_panel(const ParamNode& n, const World& w, double default_z1) {
  Panel p;
  n.get("name", p.name);
  p.from = get_point(n, "from", {}, true);
  p.to = get_point(n, "to", {}, true);
  if (std::hypot(p.to.x - p.from.x, p.to.y - p.from.y) < 1e-6) bad(n, "to", "must differ from 'from'");
  p.z1 = default_z1;
  get_range(n, "z", p.z0, p.z1);
  p.pattern = get_pattern(n, w);
  return p;
}

Pattern load_pattern(const ParamNode& n) {
  Pattern p;
  n.require("name", p.name);
  std::string type = "solid";
  n.get("type", type);
  if (type == "solid") {
    p.type = Pattern::Type::Solid;
  } else if (type == "stripes") {
    p.type = Pattern::Type::Stripes;
  } else if (type == "checker") {
    p.type = Pattern::Type::Checker;
  } else if (type == "blobs") {
    p.type = Pattern::Type::Blobs;
  } else {
    bad(n, "type", "must be solid, stripes, checker or blobs, got '" + type + "'");
  }
  n.get("low", p.low, 0.0, 1.0);
  n.get("high", p.high, 0.0, 1.0);
  n.get("period", p.period, 1e-3, 100.0);
  n.get("duty", p.duty, 0.0, 1.0);
  std::string orientation = "vertical";
  n.get("orientation", orientation);
  if (orientation != "vertical" && orientation != "horizontal") {
    bad(n, "orientation", "must be vertical or horizontal, got '" + orientation + "'");
  }
  p.vertical = orientation == "vertical";
  n.get("cell", p.cell, 1e-3, 100.0);
  n.get("count", p.count, 0, 1000);
  n.get("radius", p.radius, 1e-3, 100.0);
  n.get("seed", p.seed);
  uint64_t state = p.seed;
  for (int i = 0; i < p.count; ++i) {
    const double s = uniform01(state) * p.period;
    const double z = uniform01(state) * p.period;
    p.blob_centres.push_back({s, z});
  }
  return p;
}

Solid load_solid(const ParamNode& n, const World& w) {
  Solid s;
  n.get("name", s.name);
  std::string shape = "polygon";
  n.get("shape", shape);
  std::vector<double> pose{0.0, 0.0, 0.0};
  n.require("pose", pose);
  if (pose.size() != 3) bad(n, "pose", "must be [x, y, yaw_deg] (the shape's frame in the world)");
  const Pose2 T_world_shape{pose[0], pose[1], deg_to_rad(pose[2])};
  if (shape == "circle") {
    s.shape = Solid::Shape::Circle;
    n.require("radius", s.radius);
    if (!(s.radius > 1e-3 && s.radius < 100.0)) bad(n, "radius", "must be in (0.001, 100) m");
    s.centre = {T_world_shape.x, T_world_shape.y};
  } else if (shape == "polygon") {
    s.shape = Solid::Shape::Polygon;
    std::vector<std::vector<double>> pts;
    n.require("points", pts);
    if (pts.size() < 3 || pts.size() > 64) bad(n, "points", "needs 3 to 64 points [x, y]");
    double area2 = 0.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (pts[i].size() != 2) bad(n, "points", "must be a list of [x, y] points");
      Point2 q;
      transform_point(T_world_shape, pts[i][0], pts[i][1], q.x, q.y);
      s.vertices.push_back(q);
    }
    for (std::size_t i = 0; i < s.vertices.size(); ++i) {
      const Point2& a = s.vertices[i];
      const Point2& b = s.vertices[(i + 1) % s.vertices.size()];
      area2 += a.x * b.y - b.x * a.y;
    }
    if (std::abs(area2) < 1e-8) bad(n, "points", "encloses no area");
    if (area2 < 0.0) std::reverse(s.vertices.begin(), s.vertices.end());
    s.finalize();
  } else {
    bad(n, "shape", "must be polygon or circle, got '" + shape + "'");
  }
  get_range(n, "z", s.z0, s.z1);
  s.pattern = get_pattern(n, w);
  n.get("top_value", s.top_value, 0.0, 1.0);
  n.get("stiffness", s.stiffness, 0.01, 100.0);
  return s;
}

// Fault times: far beyond any run a world file allows (kMaxLaps of the default arena last 7.3 days),
// small enough that microseconds stay exact in an int64.
constexpr double kMaxFaultSeconds = 1e6;

template <typename Interval>
Interval load_interval(const ParamNode& n) {
  Interval f;
  n.require("start", f.start);
  n.require("duration", f.duration);
  if (!(f.start >= 0.0 && f.start <= kMaxFaultSeconds)) bad(n, "start", "must be in [0, 1e6] s");
  if (!(f.duration > 0.0 && f.duration <= kMaxFaultSeconds)) bad(n, "duration", "must be in (0, 1e6] s");
  return f;
}

// Two intervals of one fault on one sensor would make its start and end ambiguous (which frame does
// an overlapping freeze hold, which slip scale applies?): the loader refuses them.
template <typename Interval, typename SameSensor>
void refuse_overlaps(const std::vector<ParamNode>& nodes, const std::vector<Interval>& v, const std::string& key,
                     SameSensor same) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (!same(v[i], v[j])) continue;
      if (v[i].start < v[j].start + v[j].duration && v[j].start < v[i].start + v[i].duration) {
        bad(nodes[i], "start", "overlaps " + key + "[" + std::to_string(j) + "] of the same sensor");
      }
    }
  }
}

// The list `key` of `n`, refused beyond `max` items: every list of a world is short (a generated
// world's longest, lighting.changes, holds tens), and a longer one is a mistake that would cost
// the loader and the renderer in proportion (fault intervals are checked pairwise).
std::vector<ParamNode> bounded_list(const ParamNode& n, const std::string& key, std::size_t max) {
  std::vector<ParamNode> items = n.list(key);
  if (items.size() > max) {
    bad(n, key, "has " + std::to_string(items.size()) + " items, at most " + std::to_string(max));
  }
  return items;
}
constexpr std::size_t kMaxFaults = 1000;  // per kind

Faults load_faults(const ParamNode& node) {
  Faults f;
  node.get("dead_whiskers", f.dead_whiskers);
  for (std::size_t i = 0; i < f.dead_whiskers.size(); ++i) {
    const int w = f.dead_whiskers[i];
    if (w < 0 || w >= kNumBoards * kWhiskersPerBoard) bad(node, "dead_whiskers", "has whisker " + std::to_string(w) + ": indices are 0..23");
    for (std::size_t j = 0; j < i; ++j) {
      if (f.dead_whiskers[j] == w) bad(node, "dead_whiskers", "repeats whisker " + std::to_string(w));
    }
  }
  const std::vector<ParamNode> boards = bounded_list(node, "board_offline", kMaxFaults);
  for (const ParamNode& n : boards) {
    BoardOffline b = load_interval<BoardOffline>(n);
    n.require("board", b.board);
    if (b.board < 0 || b.board >= kNumBoards) bad(n, "board", "must be a board 0..5");
    f.board_offline.push_back(b);
  }
  refuse_overlaps(boards, f.board_offline, "board_offline",
                  [](const BoardOffline& a, const BoardOffline& b) { return a.board == b.board; });
  const auto any = [](const auto&, const auto&) { return true; };
  const std::vector<ParamNode> blackouts = bounded_list(node, "camera_blackout", kMaxFaults);
  for (const ParamNode& n : blackouts) f.camera_blackout.push_back(load_interval<FaultInterval>(n));
  refuse_overlaps(blackouts, f.camera_blackout, "camera_blackout", any);
  const std::vector<ParamNode> freezes = bounded_list(node, "camera_freeze", kMaxFaults);
  for (const ParamNode& n : freezes) f.camera_freeze.push_back(load_interval<FaultInterval>(n));
  refuse_overlaps(freezes, f.camera_freeze, "camera_freeze", any);
  const std::vector<ParamNode> slips = bounded_list(node, "odometry_slip", kMaxFaults);
  for (const ParamNode& n : slips) {
    OdometrySlip s = load_interval<OdometrySlip>(n);
    n.require("scale", s.scale);
    if (!(s.scale >= 0.1 && s.scale <= 10.0)) bad(n, "scale", "must be in [0.1, 10]");
    f.odometry_slip.push_back(s);
  }
  refuse_overlaps(slips, f.odometry_slip, "odometry_slip", any);
  const std::vector<ParamNode> kidnaps = bounded_list(node, "kidnap", kMaxFaults);
  for (std::size_t i = 0; i < kidnaps.size(); ++i) {
    const ParamNode& n = kidnaps[i];
    Kidnap k;
    n.require("at", k.at);
    n.require("to_angle", k.to_angle);
    if (!(k.at > 0.0 && k.at <= kMaxFaultSeconds)) bad(n, "at", "must be in (0, 1e6] s (a start elsewhere is trajectory.start_angle_deg)");
    if (!(std::abs(k.to_angle) <= kTwoPi)) bad(n, "to_angle", "must be in [-2 pi, 2 pi] rad");
    // In time order: which kidnap a pose follows must not depend on the file's order.
    if (i > 0 && !(std::llround(k.at * 1e6) > std::llround(f.kidnap.back().at * 1e6))) {
      bad(n, "at", "must be after kidnap[" + std::to_string(i - 1) + "].at (kidnaps in time order)");
    }
    f.kidnap.push_back(k);
  }
  return f;
}

}  // namespace

void Solid::finalize() {
  if (shape != Shape::Polygon || vertices.empty()) return;
  double cx = 0.0;
  double cy = 0.0;
  for (const Point2& q : vertices) {
    cx += q.x;
    cy += q.y;
  }
  centre = {cx / static_cast<double>(vertices.size()), cy / static_cast<double>(vertices.size())};
  radius = 0.0;
  for (const Point2& q : vertices) radius = std::max(radius, std::hypot(q.x - centre.x, q.y - centre.y));
  perimeter_at.assign(vertices.size() + 1, 0.0);
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const Point2& a = vertices[i];
    const Point2& b = vertices[(i + 1) % vertices.size()];
    perimeter_at[i + 1] = perimeter_at[i] + std::hypot(b.x - a.x, b.y - a.y);
  }
}

double Lighting::gain_at(double t) const {
  double g = brightness;
  for (const LightChange& c : changes) {
    if (t >= c.start && t < c.start + c.duration) g *= c.gain;
  }
  return g;
}

Pose2 Trajectory::pose_at(double t) const {
  const double sign = counter_clockwise ? 1.0 : -1.0;
  const double phi = start_angle + sign * speed * t / radius;
  return {centre.x + radius * std::cos(phi), centre.y + radius * std::sin(phi),
          wrap_angle(outwards ? phi : phi + kPi)};
}

void Trajectory::body_velocity(double& vx, double& vy, double& omega) const {
  const double sign = counter_clockwise ? 1.0 : -1.0;
  // The tangent of a counter-clockwise circle is the outward heading's left (+y) axis.
  vx = 0.0;
  vy = sign * speed * (outwards ? 1.0 : -1.0);
  omega = sign * speed / radius;
}

double Trajectory::lap_time() const { return kTwoPi * radius / speed; }

Pose2 World::base_pose_at(double t) const {
  const int64_t t_us = std::llround(t * 1e6);
  const Kidnap* last = nullptr;
  for (const Kidnap& k : faults.kidnap) {
    if (std::llround(k.at * 1e6) <= t_us) last = &k;
  }
  if (last == nullptr) return trajectory.pose_at(t);
  Trajectory moved = trajectory;
  moved.start_angle = last->to_angle;
  return moved.pose_at(t - last->at);
}

int World::pattern_index(const std::string& n) const {
  for (std::size_t i = 0; i < patterns.size(); ++i) {
    if (patterns[i].name == n) return static_cast<int>(i);
  }
  return -1;
}

void load(const ParamNode& node, World& world) {
  World w;
  node.get("name", w.name);
  node.get("floor_value", w.floor_value, 0.0, 1.0);
  node.get("sky_value", w.sky_value, 0.0, 1.0);
  for (const ParamNode& n : bounded_list(node, "patterns", 256)) {
    Pattern p = load_pattern(n);
    if (w.pattern_index(p.name) >= 0) bad(n, "name", "repeats the pattern name '" + p.name + "'");
    w.patterns.push_back(std::move(p));
  }
  double wall_height = 1.0;
  node.get("wall_height", wall_height, 0.01, 100.0);
  for (const ParamNode& n : bounded_list(node, "walls", 1000)) w.walls.push_back(load_panel(n, w, wall_height));
  for (const ParamNode& n : bounded_list(node, "visual_landmarks", 1000)) {
    w.landmarks.push_back(load_panel(n, w, wall_height));
  }
  for (const ParamNode& n : bounded_list(node, "tactile_landmarks", 1000)) {
    Solid s = load_solid(n, w);
    // A name stands for one landmark (the summary counts contacts by name): never two.
    for (const Solid& other : w.solids) {
      if (!s.name.empty() && other.name == s.name) bad(n, "name", "repeats the tactile landmark name '" + s.name + "'");
    }
    w.solids.push_back(std::move(s));
  }

  const ParamNode light = node.section("lighting");
  light.get("brightness", w.lighting.brightness, 0.0, 10.0);
  light.get("ambient", w.lighting.ambient, 0.0, 1.0);
  light.get("attenuation", w.lighting.attenuation, 0.0, 10.0);
  for (const ParamNode& n : bounded_list(light, "changes", 10000)) {
    LightChange c;
    n.require("start", c.start);
    n.get("duration", c.duration, 0.0, 1e6);
    n.get("gain", c.gain, 0.0, 100.0);
    if (!(c.start >= 0.0)) bad(n, "start", "must be >= 0 s");
    w.lighting.changes.push_back(c);
  }

  const ParamNode traj = node.section("trajectory");
  std::string type = "circle";
  traj.get("type", type);
  if (type != "circle") bad(traj, "type", "must be circle (the only trajectory implemented)");
  w.trajectory.centre = get_point(traj, "centre", w.trajectory.centre);
  traj.get("radius", w.trajectory.radius, 0.01, 100.0);
  traj.get("speed", w.trajectory.speed, 0.001, 10.0);
  double start_deg = rad_to_deg(w.trajectory.start_angle);
  traj.get("start_angle_deg", start_deg, -360.0, 360.0);
  w.trajectory.start_angle = deg_to_rad(start_deg);
  std::string facing = "outwards";
  traj.get("facing", facing);
  if (facing != "outwards" && facing != "inwards") bad(traj, "facing", "must be outwards or inwards");
  w.trajectory.outwards = facing == "outwards";
  std::string direction = "ccw";
  traj.get("direction", direction);
  if (direction != "ccw" && direction != "cw") bad(traj, "direction", "must be ccw or cw");
  w.trajectory.counter_clockwise = direction == "ccw";
  traj.get("laps", w.trajectory.laps, 1, kMaxLaps);

  const ParamNode cam = node.section("camera");
  cam.get("noise_sigma", w.camera.sigma, 0.0, 100.0);
  std::string format = "YUYV";
  cam.get("format", format);
  if (format != "YUYV" && format != "GREY" && format != "MJPEG") {
    bad(cam, "format", "must be YUYV, GREY or MJPEG, got '" + format + "'");
  }
  w.camera.format = format == "YUYV" ? CameraFormat::Yuyv : format == "GREY" ? CameraFormat::Grey : CameraFormat::Mjpeg;
  cam.get("jpeg_quality", w.camera.jpeg_quality, 1, 100);

  const ParamNode odo = node.section("odometry");
  odo.get("sigma_v", w.odometry.sigma_v, 0.0, 10.0);
  odo.get("sigma_omega", w.odometry.sigma_omega, 0.0, 10.0);
  odo.get("bias_vx", w.odometry.bias_vx, -10.0, 10.0);
  odo.get("bias_vy", w.odometry.bias_vy, -10.0, 10.0);
  odo.get("bias_omega", w.odometry.bias_omega, -10.0, 10.0);
  odo.get("scale_v", w.odometry.scale_v, 0.5, 2.0);
  odo.get("start_at_truth", w.odometry.start_at_truth);

  w.faults = load_faults(node.section("faults"));
  world = std::move(w);
}

World load_world(const ParamNode& root) {
  World w;
  load(root.section("world"), w);
  root.check_no_unknown_keys();
  return w;
}

World load_world_file(const std::string& path) { return load_world(ParamNode::from_file(path)); }

bool ray_panel(const Point2& o, const Point2& d, const Panel& p, double& t, double& s) {
  const double ex = p.to.x - p.from.x;
  const double ey = p.to.y - p.from.y;
  const double den = d.x * ey - d.y * ex;  // cross(d, e)
  if (std::abs(den) < 1e-12) return false;
  const double wx = p.from.x - o.x;
  const double wy = p.from.y - o.y;
  const double tt = (wx * ey - wy * ex) / den;
  const double u = (wx * d.y - wy * d.x) / den;
  if (tt < 0.0 || u < 0.0 || u > 1.0) return false;
  t = tt;
  s = u * std::hypot(ex, ey);
  return true;
}

int ray_solid(const Point2& o, const Point2& d, const Solid& solid, std::vector<SolidHit>& out) {
  if (solid.shape == Solid::Shape::Circle) {
    const double fx = o.x - solid.centre.x;
    const double fy = o.y - solid.centre.y;
    const double b = fx * d.x + fy * d.y;
    const double c = fx * fx + fy * fy - solid.radius * solid.radius;
    const double disc = b * b - c;
    if (disc <= 0.0) return 0;
    const double q = std::sqrt(disc);
    const double t0 = -b - q;
    const double t1 = -b + q;
    if (t1 < 0.0) return 0;
    const double a = std::atan2(fy + t0 * d.y, fx + t0 * d.x);
    out.push_back({t0, t1, wrap_angle_positive(a) * solid.radius, q / solid.radius});
    return 1;
  }
  // Polygon. A ray that misses the bounding circle misses the polygon (most rays, most of the time).
  if (!solid.perimeter_at.empty()) {
    const double fx = o.x - solid.centre.x;
    const double fy = o.y - solid.centre.y;
    const double b = fx * d.x + fy * d.y;
    const double c = fx * fx + fy * fy - solid.radius * solid.radius;
    if (c > 0.0 && (b > 0.0 || b * b - c <= 0.0)) return 0;
  }
  // Every crossing of the infinite line with an edge; sorted, consecutive pairs are the inside
  // intervals. Edges are half-open so a line through a vertex counts it once.
  struct Crossing {
    double t;
    double s;
    double cos;
  };
  Crossing xs[64];
  int n = 0;
  double perimeter = 0.0;
  const std::size_t nv = solid.vertices.size();
  for (std::size_t i = 0; i < nv; ++i) {
    const Point2& a = solid.vertices[i];
    const Point2& b = solid.vertices[(i + 1) % nv];
    const double ex = b.x - a.x;
    const double ey = b.y - a.y;
    const bool cached = solid.perimeter_at.size() == nv + 1;
    const double len = cached ? solid.perimeter_at[i + 1] - solid.perimeter_at[i] : std::hypot(ex, ey);
    const double den = d.x * ey - d.y * ex;
    if (std::abs(den) > 1e-12 && len > 0.0) {
      const double wx = a.x - o.x;
      const double wy = a.y - o.y;
      const double u = (wx * d.y - wy * d.x) / den;
      if (u >= 0.0 && u < 1.0 && n < 64) {
        xs[n++] = {(wx * ey - wy * ex) / den, perimeter + u * len, std::abs(den) / len};
      }
    }
    perimeter += len;
  }
  std::sort(xs, xs + n, [](const Crossing& p, const Crossing& q) { return p.t < q.t; });
  int added = 0;
  for (int i = 0; i + 1 < n; i += 2) {
    if (xs[i + 1].t < 0.0) continue;
    out.push_back({xs[i].t, xs[i + 1].t, xs[i].s, xs[i].cos});
    ++added;
  }
  return added;
}

}  // namespace whiskeye::sim
