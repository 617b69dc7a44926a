// World generator and aliasing check (see world_generator.h).
#include "whiskeye/sim/world_generator.h"

#include "whiskeye/sim/renderer.h"
#include "whiskeye/sim/whisker_contact.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace whiskeye::sim {

namespace {

// splitmix64: fully specified, so a world seed gives the same world on every platform.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform(double a, double b) { return a + (b - a) * (static_cast<double>(next() >> 11) * 0x1.0p-53); }
  double uniform(const Range& r) { return uniform(r.min, r.max); }
  // Inclusive.
  int integer(int a, int b) { return a + static_cast<int>(next() % static_cast<uint64_t>(b - a + 1)); }
  int integer(const Range& r) { return integer(static_cast<int>(std::lround(r.min)), static_cast<int>(std::lround(r.max))); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  template <typename T>
  void shuffle(std::vector<T>& v) {
    for (std::size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[static_cast<std::size_t>(next() % i)]);
  }

 private:
  uint64_t state_;
};

std::string num(double v, int decimals = 4) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  // "-0.0000" reads badly and is the same number.
  if (s.find_first_not_of("-0.") == std::string::npos) s = std::string(buf + (buf[0] == '-' ? 1 : 0));
  return s;
}

// Polar angle (deg) that `m` metres of the head's path span.
double m_to_deg(double m, double head_r) { return m / head_r * 180.0 / kPi; }

// Half a whisk cycle's (1 s) travel along the path, in degrees: how far a place's touch reaches.
double half_cycle_deg(double speed, double head_r) { return 0.5 * speed / head_r * 180.0 / kPi; }

// A pair of views looks alike within this matcher distance (margin × slamd's visual match limit).
double alike_limit(const AliasCheckParams& p) { return p.margin * p.match.threshold_visual * p.match.sigma_visual; }

double circular_deg(double a) {
  a = std::fmod(a, 360.0);
  return a < 0.0 ? a + 360.0 : a;
}

// ---- the libraries the generator draws from ----

// Tactile landmark shapes, in the shape frame: x radially outwards from the path, y along it, the
// face nearest the path at x = 0.
struct ObjectShape {
  const char* name;
  bool circle;
  double radius;  // circle
  std::vector<std::pair<double, double>> points;
};

const std::vector<ObjectShape>& object_library() {
  static const std::vector<ObjectShape> lib{
      {"corrugated_box", false, 0.0,
       {{0.10, -0.08}, {0.10, 0.08}, {0.0, 0.08}, {0.015, 0.06}, {0.0, 0.04}, {0.015, 0.02}, {0.0, 0.0},
        {0.015, -0.02}, {0.0, -0.04}, {0.015, -0.06}, {0.0, -0.08}}},
      {"flat_box", false, 0.0, {{0.10, -0.08}, {0.10, 0.08}, {0.0, 0.08}, {0.0, -0.08}}},
      {"wide_box", false, 0.0, {{0.08, -0.15}, {0.08, 0.15}, {0.0, 0.15}, {0.0, -0.15}}},
      {"wedge", false, 0.0, {{0.12, -0.09}, {0.12, 0.09}, {0.0, 0.0}}},
      {"post", true, 0.06, {}},
      {"drum", true, 0.12, {}},
  };
  return lib;
}

// Tactile landmarks stand at most this far along the path from their centre (for spacing them).
constexpr double kObjectHalfLength = 0.15;
// Whiskers reach at most this far from the head (robot.yaml's longest is 0.17 m).
constexpr double kReach = 0.20;
// The near face of a tactile landmark is drawn 0.08-0.10 m outside the head's path.
constexpr double kMinGap = 0.08, kMaxGap = 0.10;

struct PatternSpec {
  std::string name;
  std::string fields;  // the YAML map's fields after the name
};

struct LandmarkSpec {
  int wall = 0;        // 0 east, 1 north, 2 west, 3 south (outward normal at 90°·wall)
  int slot = 0;        // offset from the wall's normal: kSlotDeg[slot]
  double width = 1.0;  // m
  double z0 = 0.25;
  double z1 = 1.05;
  int pattern = 0;
  std::string name;
};

constexpr double kSlotDeg[3] = {-28.0, 0.0, 28.0};

struct ObjectSpec {
  int shape = 0;        // index into object_library()
  double angle_deg = 0;  // polar angle of the path where it stands
  std::string name;
};

struct Draft {
  std::string name = "generated";
  double side = 6.0;
  double wall_grey = 0.55;
  double floor = 0.3;
  std::vector<PatternSpec> patterns;  // [0] = wall
  std::vector<LandmarkSpec> landmarks;
  std::vector<ObjectSpec> objects;
  double gap = 0.10;  // near face of every tactile landmark: this far outside the head's path
  double radius = 1.0, speed = 0.1, start_deg = 0.0;
  bool ccw = true;
  int laps = 4;
  double camera_noise = 2.0;
  double sigma_v = 0.005, sigma_omega = 0.003, bias_vy = 0.002, bias_omega = 0.002;
  std::vector<LightChange> light_changes;
  std::string faults_yaml;
  std::string stress_note;
};

// A wall landmark pattern, drawn; `k` makes the name unique.
PatternSpec draw_pattern(Rng& rng, int k) {
  PatternSpec p;
  p.name = "p";  // appended, not "p" + std::string: GCC 12 -O3 -Wrestrict (bug 105329)
  p.name += std::to_string(k);
  const double low = rng.uniform(0.05, 0.2);
  const double high = rng.uniform(0.8, 0.95);
  const std::string lh = ", low: " + num(low, 2) + ", high: " + num(high, 2);
  switch (rng.integer(0, 4)) {
    case 0:
      p.name += "_vstripes";
      p.fields = "type: stripes, orientation: vertical, period: " + num(rng.uniform(0.14, 0.34), 3) + ", duty: 0.5" + lh;
      break;
    case 1:
      p.name += "_hstripes";
      p.fields = "type: stripes, orientation: horizontal, period: " + num(rng.uniform(0.12, 0.26), 3) + ", duty: 0.5" + lh;
      break;
    case 2:
      p.name += "_checker";
      p.fields = "type: checker, cell: " + num(rng.uniform(0.14, 0.3), 3) + lh;
      break;
    case 3:
      p.name += "_blobs";
      p.fields = "type: blobs, period: " + num(rng.uniform(0.5, 0.7), 3) + ", count: " + std::to_string(rng.integer(4, 6)) +
                 ", radius: " + num(rng.uniform(0.07, 0.1), 3) + ", seed: " + std::to_string(rng.integer(1, 9999)) + lh;
      break;
    default:
      p.name += "_dark";
      p.fields = "type: solid, high: " + num(rng.uniform(0.08, 0.2), 2);
      break;
  }
  return p;
}

double head_radius(const Draft& d, const RobotGeometry& robot) { return head_path_radius(d.radius, robot); }

// Angle (deg) of the path that one metre along the head's path spans.
double deg_per_m(const Draft& d, const RobotGeometry& robot) { return 180.0 / (kPi * head_radius(d, robot)); }

std::string to_yaml(const Draft& d, const RobotGeometry& robot) {
  std::ostringstream y;
  const double h = d.side / 2.0;
  y << "world:\n  name: " << d.name << "\n";
  y << "  floor_value: " << num(d.floor, 2) << "\n  sky_value: 0.85\n  wall_height: 1.2\n";
  y << "  patterns:\n";
  for (const PatternSpec& p : d.patterns) y << "    - {name: " << p.name << ", " << p.fields << "}\n";
  y << "  walls:\n";
  const char* wall_names[4] = {"east", "north", "west", "south"};
  for (int w = 0; w < 4; ++w) {
    // Corners counter-clockwise: east wall from (h, -h) to (h, h), and so on.
    const double a0 = deg_to_rad(90.0 * w - 45.0);
    const double a1 = deg_to_rad(90.0 * w + 45.0);
    const double r = h * std::sqrt(2.0);
    y << "    - {name: " << wall_names[w] << ", from: [" << num(r * std::cos(a0)) << ", " << num(r * std::sin(a0))
      << "], to: [" << num(r * std::cos(a1)) << ", " << num(r * std::sin(a1)) << "], pattern: " << d.patterns[0].name
      << "}\n";
  }
  y << "  # from -> to runs left to right as seen from the centre, so landmarks alike on two walls\n"
       "  # look alike from the two places that face them.\n";
  y << "  visual_landmarks:\n";
  for (const LandmarkSpec& l : d.landmarks) {
    const double alpha = deg_to_rad(90.0 * l.wall);
    const double nx = std::cos(alpha), ny = std::sin(alpha);  // outward normal
    const double rx = std::sin(alpha), ry = -std::cos(alpha);  // "right" seen from the centre
    const double off = -h * std::tan(deg_to_rad(kSlotDeg[l.slot]));  // along "right"
    const double cx = nx * h + rx * off, cy = ny * h + ry * off;
    y << "    - {name: " << l.name << ", from: [" << num(cx - rx * l.width / 2) << ", " << num(cy - ry * l.width / 2)
      << "], to: [" << num(cx + rx * l.width / 2) << ", " << num(cy + ry * l.width / 2) << "], z: [" << num(l.z0, 3)
      << ", " << num(l.z1, 3) << "], pattern: " << d.patterns[static_cast<std::size_t>(l.pattern)].name << "}\n";
  }
  y << "  # Shape frames: x radially outwards from the path, y along it; the near face " << num(d.gap, 3)
    << " m outside the head's path.\n";
  y << "  tactile_landmarks:\n";
  const double r0 = head_radius(d, robot) + d.gap;
  for (const ObjectSpec& o : d.objects) {
    const ObjectShape& s = object_library()[static_cast<std::size_t>(o.shape)];
    const double a = deg_to_rad(o.angle_deg);
    const double r = s.circle ? r0 + s.radius : r0;
    y << "    - {name: " << o.name << ", shape: " << (s.circle ? "circle" : "polygon") << ", pose: [" << num(r * std::cos(a))
      << ", " << num(r * std::sin(a)) << ", " << num(o.angle_deg, 3) << "]";
    if (s.circle) {
      y << ", radius: " << num(s.radius, 3);
    } else {
      y << ", points: [";
      for (std::size_t i = 0; i < s.points.size(); ++i) {
        y << (i ? ", " : "") << "[" << num(s.points[i].first, 3) << ", " << num(s.points[i].second, 3) << "]";
      }
      y << "]";
    }
    y << ", z: [0.0, 0.31], pattern: object, top_value: 0.6}\n";
  }
  y << "  lighting:\n    brightness: 1.0\n    ambient: 0.6\n    attenuation: 0.05\n    changes: [";
  for (std::size_t i = 0; i < d.light_changes.size(); ++i) {
    const LightChange& c = d.light_changes[i];
    y << (i ? ", " : "") << "{start: " << num(c.start, 1) << ", duration: " << num(c.duration, 2)
      << ", gain: " << num(c.gain, 2) << "}";
  }
  y << "]\n";
  y << "  trajectory: {type: circle, centre: [0.0, 0.0], radius: " << num(d.radius, 3) << ", speed: " << num(d.speed, 4)
    << ", start_angle_deg: " << num(d.start_deg, 1) << ", facing: outwards, direction: " << (d.ccw ? "ccw" : "cw")
    << ", laps: " << d.laps << "}\n";
  y << "  camera: {noise_sigma: " << num(d.camera_noise, 2) << ", format: YUYV}\n";
  y << "  odometry: {sigma_v: " << num(d.sigma_v, 5) << ", sigma_omega: " << num(d.sigma_omega, 5)
    << ", bias_vx: 0.0, bias_vy: " << num(d.bias_vy, 5) << ", bias_omega: " << num(d.bias_omega, 5)
    << ", scale_v: 1.0, start_at_truth: false}\n";
  y << d.faults_yaml;
  return y.str();
}

World load_yaml(const std::string& yaml) {
  const ParamNode root = ParamNode::from_string(yaml, "<generated world>");
  World w;
  load(root.section("world"), w);
  root.check_no_unknown_keys();
  return w;
}

// ---- the check ----

// Pose of the base at polar angle `deg` of the world's circle (facing as the trajectory does).
Pose2 pose_at_angle(const Trajectory& trajectory, double deg) {
  Trajectory t = trajectory;
  t.start_angle = deg_to_rad(deg);
  return t.pose_at(0.0);
}

struct Views {
  std::vector<double> angles_deg;
  int w = 0, h = 0;
  std::vector<std::vector<uint8_t>> column_major;  // one template per angle, the matcher's layout

  // The view rendered nearest to polar angle `deg`.
  int index_of(double deg) const {
    const int n = static_cast<int>(angles_deg.size());
    return static_cast<int>(std::lround(circular_deg(deg) / (360.0 / n))) % n;
  }
};

Views render_views(const World& world, const RobotGeometry& robot, const AliasCheckParams& p) {
  World quiet = world;
  quiet.camera.sigma = 0.0;
  quiet.lighting.changes.clear();
  Renderer renderer(quiet, robot);
  FastRng rng(1);
  Views v;
  const int n = std::max(1, static_cast<int>(std::lround(360.0 / p.angle_step_deg)));
  std::vector<uint8_t> grey;
  std::vector<float> f;
  for (int k = 0; k < n; ++k) {
    const double a = 360.0 * k / n;
    renderer.render(pose_at_angle(quiet.trajectory, a), 0.0, rng, grey);
    f.resize(grey.size());
    for (std::size_t i = 0; i < grey.size(); ++i) f[i] = static_cast<float>(grey[i]) / 255.0f;
    const slam::VisualTemplate t =
        slam::make_visual_template_from_grey(f.data(), renderer.width(), renderer.height(), renderer.width(), p.visual);
    v.w = t.width;
    v.h = t.height;
    std::vector<uint8_t> cm(t.pixels.size());
    for (int y = 0; y < t.height; ++y) {
      for (int x = 0; x < t.width; ++x) cm[static_cast<std::size_t>(x * t.height + y)] = t.pixels[static_cast<std::size_t>(y * t.width + x)];
    }
    v.angles_deg.push_back(a);
    v.column_major.push_back(std::move(cm));
  }
  return v;
}

double circular_gap_deg(double a, double b) {
  const double d = std::abs(circular_deg(a - b));
  return std::min(d, 360.0 - d);
}

// Per solid: the first-touch angle of every whisker at each offset of the passage (NaN: that
// whisker touches nothing of this solid there), and the polar angles over which it is touched.
struct TouchProfile {
  double centre_deg = 0.0;
  std::vector<double> theta;  // offsets × whiskers
  double touched_from = 0.0, touched_to = 0.0;  // offsets (deg) of the first / last touch
  bool touched = false;
};

constexpr double kProfileStepDeg = 0.5;

std::vector<TouchProfile> touch_profiles(const World& world, const RobotGeometry& robot) {
  const Trajectory& t = world.trajectory;
  const double half_deg = m_to_deg(kObjectHalfLength + kReach + 0.05, head_path_radius(t.radius, robot));
  const int steps = static_cast<int>(std::ceil(half_deg / kProfileStepDeg));
  std::vector<TouchProfile> out;
  for (std::size_t s = 0; s < world.solids.size(); ++s) {
    TouchProfile p;
    const Solid& solid = world.solids[s];
    p.centre_deg = circular_deg(rad_to_deg(std::atan2(solid.centre.y - t.centre.y, solid.centre.x - t.centre.x)));
    for (int k = -steps; k <= steps; ++k) {
      const double off = k * kProfileStepDeg;
      const Pose2 T_world_head = compose(pose_at_angle(t, p.centre_deg + off), robot.T_base_head);
      for (int w = 0; w < kNumWhiskers; ++w) {
        const auto c = find_whisker_contact(world, robot, T_world_head, w);
        const bool mine = c && c->solid == static_cast<int>(s);
        p.theta.push_back(mine ? c->theta : std::numeric_limits<double>::quiet_NaN());
        if (mine) {
          if (!p.touched) p.touched_from = off;
          p.touched = true;
          p.touched_to = off;
        }
      }
    }
    out.push_back(std::move(p));
  }
  return out;
}

// Mean |Δθ| over the whiskers touching in both, or infinity when the two disagree on where a
// whisker touches at all (more than a couple of entries at the edges of a touch).
double profile_distance(const TouchProfile& a, const TouchProfile& b) {
  int both = 0, mismatch = 0;
  double sum = 0.0;
  for (std::size_t i = 0; i < a.theta.size() && i < b.theta.size(); ++i) {
    const bool fa = std::isfinite(a.theta[i]), fb = std::isfinite(b.theta[i]);
    if (fa && fb) {
      ++both;
      sum += std::abs(a.theta[i] - b.theta[i]);
    } else if (fa != fb) {
      ++mismatch;
    }
  }
  if (both == 0 || mismatch > std::max(2, both / 50)) return std::numeric_limits<double>::infinity();
  return sum / both;
}

}  // namespace

void validate(const GeneratorOptions& o) {
  if (o.family != "aliased" && o.family != "stress") {
    throw GeneratorOptionError("--family: unknown family '" + o.family + "' (aliased or stress)");
  }
  auto range = [](const char* name, const Range& r, double lo, double hi) {
    if (!(std::isfinite(r.min) && std::isfinite(r.max)) || r.min > r.max) {
      throw GeneratorOptionError(std::string(name) + ": the range " + num(r.min, 3) + ".." + num(r.max, 3) + " is empty");
    }
    if (r.min < lo || r.max > hi) {
      throw GeneratorOptionError(std::string(name) + ": the range " + num(r.min, 3) + ".." + num(r.max, 3) +
                                 " is outside " + num(lo, 3) + ".." + num(hi, 3));
    }
  };
  range("--arena-side", o.side, 4.0, 20.0);
  range("--wall-landmarks", o.wall_landmarks, 4, 12);
  range("--tactile-landmarks", o.tactile_landmarks, 2, 12);
  range("--radius", o.radius, 0.5, 2.0);
  range("--speed", o.speed, 0.02, 0.5);
  range("--gen-laps", o.laps, 1, 1000);
  range("--odometry-bias-scale", o.odometry_bias_scale, 0.0, 20.0);
  range("--odometry-noise-scale", o.odometry_noise_scale, 0.0, 20.0);
  range("--camera-noise", o.camera_noise, 0.0, 50.0);
  if (std::floor(o.wall_landmarks.min) != o.wall_landmarks.min || std::floor(o.wall_landmarks.max) != o.wall_landmarks.max ||
      std::floor(o.tactile_landmarks.min) != o.tactile_landmarks.min ||
      std::floor(o.tactile_landmarks.max) != o.tactile_landmarks.max || std::floor(o.laps.min) != o.laps.min ||
      std::floor(o.laps.max) != o.laps.max) {
    throw GeneratorOptionError("--wall-landmarks, --tactile-landmarks and --gen-laps take whole numbers");
  }
  if (!(o.lighting_change_probability >= 0.0 && o.lighting_change_probability <= 1.0)) {
    throw GeneratorOptionError("--lighting-probability: must be in 0..1");
  }
  if (o.max_attempts < 1) throw GeneratorOptionError("--max-attempts: must be at least 1");
  if (o.kidnaps < 0 || o.kidnaps > kMaxKidnaps) {
    throw GeneratorOptionError("--kidnaps: must be in 0.." + std::to_string(kMaxKidnaps));
  }
  if (o.kidnaps > 0 && o.laps.min < 2) throw GeneratorOptionError("--kidnaps: needs at least 2 laps (--gen-laps)");
  // The aliased family's premise needs a feel-alike pair and a shape that differs from it.
  if (o.family == "aliased" && o.tactile_landmarks.max < 3) {
    throw GeneratorOptionError("--tactile-landmarks: the aliased family needs at least 3 (a pair that feels alike and "
                               "another shape), the range allows at most " + num(o.tactile_landmarks.max, 0));
  }
}

AliasReport check_aliasing(const World& world, const RobotGeometry& robot, const AliasCheckParams& p) {
  AliasReport report;
  const Views v = render_views(world, robot, p);
  const int n = static_cast<int>(v.angles_deg.size());
  const Trajectory& t = world.trajectory;
  const double head_r = head_path_radius(t.radius, robot);
  const double min_sep_deg = m_to_deg(p.min_separation_m, head_r);
  const double limit = alike_limit(p);

  // Every pair of places far enough apart: the matcher's own distance.
  std::vector<double> dist(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), 1.0);
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (circular_gap_deg(v.angles_deg[static_cast<std::size_t>(i)], v.angles_deg[static_cast<std::size_t>(j)]) < min_sep_deg) continue;
      int shift = 0;
      const double d = slam::TemplateStore::visual_distance(v.column_major[static_cast<std::size_t>(i)].data(),
                                                            v.column_major[static_cast<std::size_t>(j)].data(), v.w, v.h,
                                                            p.match.shift_max, p.match.shift_step, &shift);
      dist[static_cast<std::size_t>(i * n + j)] = dist[static_cast<std::size_t>(j * n + i)] = d;
    }
  }

  // Look-alike pairs of places: the connected groups of alike pairs of views (i, j) — a stretch of
  // path [a0, a1] whose views match those along another stretch [b0, b1] forms one group. Each group
  // gives two places; a group whose two stretches overlap (a stretch alike with itself shifted, as
  // in a point-symmetric arena) cannot be told apart by what is touched along it.
  std::vector<int> group(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), -1);
  std::vector<std::vector<std::pair<int, int>>> groups;
  auto is_alike = [&](int i, int j) { return i != j && dist[static_cast<std::size_t>(i * n + j)] <= limit; };
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (!is_alike(i, j) || group[static_cast<std::size_t>(i * n + j)] >= 0) continue;
      const int g = static_cast<int>(groups.size());
      groups.emplace_back();
      std::vector<std::pair<int, int>> stack{{i, j}};
      group[static_cast<std::size_t>(i * n + j)] = group[static_cast<std::size_t>(j * n + i)] = g;
      while (!stack.empty()) {
        const auto [ci, cj] = stack.back();
        stack.pop_back();
        groups.back().push_back({ci, cj});
        for (int di = -1; di <= 1; ++di) {
          for (int dj = -1; dj <= 1; ++dj) {
            const int ni = (ci + di + n) % n, nj = (cj + dj + n) % n;
            if (!is_alike(ni, nj) || group[static_cast<std::size_t>(ni * n + nj)] >= 0) continue;
            group[static_cast<std::size_t>(ni * n + nj)] = group[static_cast<std::size_t>(nj * n + ni)] = g;
            stack.push_back({ni, nj});
          }
        }
      }
    }
  }
  // The shortest circular stretch holding every index of a set of views.
  auto hull = [&](std::vector<int> idx) {
    std::sort(idx.begin(), idx.end());
    idx.erase(std::unique(idx.begin(), idx.end()), idx.end());
    int gap_at = 0, gap = -1;
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const int next = k + 1 < idx.size() ? idx[k + 1] : idx[0] + n;
      if (next - idx[k] > gap) {
        gap = next - idx[k];
        gap_at = static_cast<int>(k);
      }
    }
    const int from = idx[(static_cast<std::size_t>(gap_at) + 1) % idx.size()];
    const int to = idx[static_cast<std::size_t>(gap_at)];
    return std::make_pair(from, to);
  };
  auto in_hull = [&](std::pair<int, int> h, int x) { return (x - h.first + n) % n <= (h.second - h.first + n) % n; };
  // A group may be a long band (a point-symmetric stretch of arena: every view alike with the one
  // opposite), or one stretch alike with several: it is cut into places at most max_place_m long on
  // both sides, each with its look-alike partner.
  const double place_deg = m_to_deg(p.max_place_m, head_r);
  std::vector<bool> self_alike;
  std::vector<LookAlikePair> closest;
  for (const auto& cells : groups) {
    // Orient every cell so that its first view is on the same side as the group's first cell's.
    std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> segments;
    const int ref = cells.front().first;
    for (const auto& [ci, cj] : cells) {
      const bool flip = circular_gap_deg(v.angles_deg[static_cast<std::size_t>(cj)], v.angles_deg[static_cast<std::size_t>(ref)]) <
                        circular_gap_deg(v.angles_deg[static_cast<std::size_t>(ci)], v.angles_deg[static_cast<std::size_t>(ref)]);
      const int ia = flip ? cj : ci, ib = flip ? ci : cj;
      // Cut on both sides: one stretch can look like several others.
      segments[{static_cast<int>(v.angles_deg[static_cast<std::size_t>(ia)] / place_deg),
                static_cast<int>(v.angles_deg[static_cast<std::size_t>(ib)] / place_deg)}]
          .push_back({ia, ib});
    }
    for (const auto& [bin, seg] : segments) {
      std::vector<int> side_a, side_b;
      LookAlikePair best{0, 0, 2.0};
      for (const auto& [ia, ib] : seg) {
        side_a.push_back(ia);
        side_b.push_back(ib);
        const double d = dist[static_cast<std::size_t>(ia * n + ib)];
        if (d < best.distance) best = {v.angles_deg[static_cast<std::size_t>(ia)], v.angles_deg[static_cast<std::size_t>(ib)], d};
      }
      const auto ha = hull(side_a), hb = hull(side_b);
      bool overlap = false;
      for (int x : side_a) overlap = overlap || in_hull(hb, x);
      for (int x : side_b) overlap = overlap || in_hull(ha, x);
      self_alike.push_back(overlap);
      report.places.push_back({v.angles_deg[static_cast<std::size_t>(ha.first)], v.angles_deg[static_cast<std::size_t>(ha.second)], {}});
      report.places.push_back({v.angles_deg[static_cast<std::size_t>(hb.first)], v.angles_deg[static_cast<std::size_t>(hb.second)], {}});
      closest.push_back(best);
    }
  }

  // Feel-alike classes: solids whose passages feel the same, grouped (first member names the class).
  const std::vector<TouchProfile> prof = touch_profiles(world, robot);
  std::vector<int> cls(world.solids.size(), -1);
  for (std::size_t a = 0; a < prof.size(); ++a) {
    if (cls[a] >= 0) continue;
    cls[a] = static_cast<int>(report.feel_alike_classes.size());
    report.feel_alike_classes.push_back({world.solids[a].name});
    for (std::size_t b = a + 1; b < prof.size(); ++b) {
      if (cls[b] < 0 && profile_distance(prof[a], prof[b]) <= p.feel_alike_tolerance_rad) {
        cls[b] = cls[a];
        report.feel_alike_classes.back().push_back(world.solids[b].name);
      }
    }
  }
  // Two alike landmarks where the views differ (the touch alone is aliased there).
  for (std::size_t a = 0; a < prof.size(); ++a) {
    for (std::size_t b = a + 1; b < prof.size(); ++b) {
      if (cls[a] != cls[b]) continue;
      const int ia = v.index_of(prof[a].centre_deg), ib = v.index_of(prof[b].centre_deg);
      const double d = dist[static_cast<std::size_t>(ia * n + ib)];
      if (d > limit) report.feel_alike_pairs_apart.emplace_back(world.solids[a].name, world.solids[b].name);
    }
  }

  // What is touched along each place (the place widened by half a whisk cycle's travel each way).
  const double widen_deg = half_cycle_deg(t.speed, head_r) + p.angle_step_deg / 2;
  for (AliasedPlace& place : report.places) {
    std::set<std::string> touched;
    const double span = circular_deg(place.to_deg - place.from_deg) + 2 * widen_deg;
    for (std::size_t s = 0; s < prof.size(); ++s) {
      if (!prof[s].touched) continue;
      // The solid's touched interval, relative to the widened place's start.
      const double a0 = circular_deg(prof[s].centre_deg + prof[s].touched_from - (place.from_deg - widen_deg));
      const double a1 = a0 + (prof[s].touched_to - prof[s].touched_from);
      if (a0 <= span || a1 >= 360.0) {
        // A class is named by its members: "box_1~box_4" feel alike.
        std::string name;
        for (const std::string& m : report.feel_alike_classes[static_cast<std::size_t>(cls[s])]) name += (name.empty() ? "" : "~") + m;
        touched.insert(name);
      }
    }
    place.touched.assign(touched.begin(), touched.end());
  }

  for (std::size_t g = 0; g < closest.size(); ++g) {
    const std::pair<int, int> key{static_cast<int>(2 * g), static_cast<int>(2 * g + 1)};
    if (self_alike[g]) {
      report.featureless.push_back(key);
      continue;
    }
    report.place_pairs.push_back(key);
    report.pairs.push_back(closest[g]);
    if (report.places[2 * g].touched == report.places[2 * g + 1].touched) report.untold_pairs.push_back(key);
  }
  return report;
}

namespace {

// The standard fault set of the robust-SLAM issue, at drawn times within the run.
std::string draw_faults(Rng& rng, double duration) {
  std::vector<int> whiskers(kNumWhiskers);
  for (int w = 0; w < kNumWhiskers; ++w) whiskers[static_cast<std::size_t>(w)] = w;
  rng.shuffle(whiskers);
  std::vector<int> dead(whiskers.begin(), whiskers.begin() + 4);
  std::sort(dead.begin(), dead.end());
  std::ostringstream y;
  y << "  faults:\n    dead_whiskers: [";
  for (std::size_t i = 0; i < dead.size(); ++i) y << (i ? ", " : "") << dead[i];
  y << "]\n";
  auto start = [&](double length) { return num(rng.uniform(0.15 * duration, std::max(0.15 * duration, 0.9 * duration - length)), 1); };
  y << "    board_offline: [{board: " << rng.integer(0, 5) << ", start: " << start(30.0) << ", duration: 30.0}]\n";
  y << "    camera_blackout: [{start: " << start(10.0) << ", duration: 10.0}]\n";
  y << "    odometry_slip: [{start: " << start(10.0) << ", duration: 10.0, scale: " << (rng.chance(0.5) ? "1.2" : "0.8")
    << "}]\n";
  return y.str();
}

// Kidnaps after the first lap (the place has been mapped): the rest of the run is shared out, and
// each kidnap is followed by at least a lap before the next one and the end where the run is long
// enough (else by half its share); each to a point of the path 90-270 deg of polar angle from where
// the robot is then. Times and angles are rounded as written, so the file says what was drawn.
std::string draw_kidnaps(Rng& rng, const Draft& d, int n) {
  const double lap = 2.0 * kPi * d.radius / d.speed;
  const double share = (d.laps - 1) * lap / n;
  const double slack = share >= lap + 0.2 ? share - lap - 0.2 : 0.5 * share;
  const double sign = d.ccw ? 1.0 : -1.0;
  double t_prev = 0.0;
  double angle_prev = deg_to_rad(d.start_deg);
  std::ostringstream y;
  y << "    kidnap: [";
  for (int i = 0; i < n; ++i) {
    const double t = std::ceil((lap + i * share + rng.uniform(0.0, slack)) * 10.0) / 10.0;
    const double here = angle_prev + sign * d.speed * (t - t_prev) / d.radius;
    const double to = std::round(wrap_angle(here + deg_to_rad(rng.uniform(90.0, 270.0))) * 1e4) / 1e4;
    y << (i ? ", " : "") << "{at: " << num(t, 1) << ", to_angle: " << num(to, 4) << "}";
    t_prev = t;
    angle_prev = to;
  }
  y << "]\n";
  return y.str();
}

void draw_layout(Rng& rng, const GeneratorOptions& o, Draft& d) {
  d = Draft{};
  d.side = rng.uniform(o.side);
  d.wall_grey = rng.uniform(0.5, 0.6);
  d.floor = rng.uniform(0.25, 0.35);
  d.patterns.push_back({"wall", "type: solid, high: " + num(d.wall_grey, 2)});
  d.patterns.push_back({"object", "type: stripes, orientation: horizontal, period: 0.08, duty: 0.5, low: 0.25, high: 0.40"});
  d.radius = rng.uniform(o.radius);
  d.speed = rng.uniform(o.speed);
  d.start_deg = rng.uniform(0.0, 360.0);
  d.ccw = rng.chance(0.5);
  d.laps = rng.integer(o.laps);
  const double bias = rng.uniform(o.odometry_bias_scale);
  const double noise = rng.uniform(o.odometry_noise_scale);
  d.bias_vy = 0.002 * bias * (rng.chance(0.5) ? 1.0 : -1.0);
  d.bias_omega = 0.002 * rng.uniform(o.odometry_bias_scale) * (rng.chance(0.5) ? 1.0 : -1.0);
  d.sigma_v = 0.005 * noise;
  d.sigma_omega = 0.003 * noise;
  d.camera_noise = rng.uniform(o.camera_noise);
  d.gap = rng.uniform(kMinGap, kMaxGap);
  const double duration = d.laps * 2.0 * kPi * d.radius / d.speed;
  if (rng.chance(o.lighting_change_probability)) {
    if (rng.chance(0.5)) {
      d.light_changes.push_back({rng.uniform(0.1, 0.9) * duration, rng.uniform(0.3, 1.0), rng.uniform(1.4, 2.0)});
    } else {
      d.light_changes.push_back({rng.uniform(0.1, 0.8) * duration, rng.uniform(5.0, 20.0), rng.uniform(0.5, 0.75)});
    }
  }

  // Wall landmarks in 12 slots (3 per wall). Look-alike pairs come from the arena's 90° symmetry:
  // a wall whose landmarks are copied, slot for slot, onto another wall looks alike from the two
  // stretches of path that face them (what is beside a landmark is in view too, so a copied wall
  // aliases where a lone copied landmark often does not). The other two walls are copied as well, or
  // share one landmark at the same slot and get landmarks of their own; the check decides what
  // really looks alike.
  const int count = rng.integer(o.wall_landmarks);
  std::vector<int> walls{0, 1, 2, 3};
  rng.shuffle(walls);
  int k = 0;
  // L0, L1, ... and the tag. A char, not a one-character string: GCC 12 at -O3 raises a bogus
  // -Wrestrict on "x" + std::string&& (GCC bug 105329), which breaks the Release build.
  auto next_name = [&](const std::string& tag) { return 'L' + std::to_string(k++) + tag; };
  auto new_landmark = [&](int wall, int slot, int pattern, const std::string& tag) {
    LandmarkSpec l;
    l.wall = wall;
    l.slot = slot;
    l.width = rng.uniform(0.8, std::min(1.4, 0.85 * d.side / 2 * std::tan(deg_to_rad(28.0))));
    l.z0 = rng.uniform(0.15, 0.3);
    l.z1 = rng.uniform(0.95, 1.1);
    l.pattern = pattern;
    l.name = next_name(tag);
    return l;
  };
  auto new_pattern = [&]() {
    d.patterns.push_back(draw_pattern(rng, static_cast<int>(d.patterns.size())));
    return static_cast<int>(d.patterns.size()) - 1;
  };
  auto random_slots = [&](int n) {
    std::vector<int> slots{0, 1, 2};
    rng.shuffle(slots);
    slots.resize(static_cast<std::size_t>(n));
    return slots;
  };
  auto copy_wall = [&](int from, int to, int n, int twin) {
    for (int slot : random_slots(n)) {
      LandmarkSpec a = new_landmark(from, slot, new_pattern(), "_twin" + std::to_string(twin));
      LandmarkSpec b = a;
      b.wall = to;
      b.name = next_name("_twin" + std::to_string(twin));
      d.landmarks.push_back(a);
      d.landmarks.push_back(b);
    }
  };
  // First pair: 1-2 landmarks on wall A, copied onto wall B.
  const int n_first = count >= 6 ? rng.integer(1, 2) : 1;
  copy_wall(walls[0], walls[1], n_first, 0);
  int left = count - 2 * n_first;
  // Two copies on opposite walls would make the arena point-symmetric: every view alike with the
  // one opposite, which no touch can tell apart along the whole lap.
  const bool adjacent = (walls[0] - walls[1] + 4) % 4 != 2;
  if (adjacent && left % 2 == 0 && rng.chance(0.5)) {
    copy_wall(walls[2], walls[3], std::min(3, left / 2), 1);  // second pair: the other two walls alike as well
  } else {
    // Second pair: one landmark at the centre of walls C and D, then landmarks of their own.
    const int slot = 1;
    const int pattern = new_pattern();
    LandmarkSpec a = new_landmark(walls[2], slot, pattern, "_twin1");
    LandmarkSpec b = a;
    b.wall = walls[3];
    b.name = "L" + std::to_string(k++) + "_twin1";
    d.landmarks.push_back(a);
    d.landmarks.push_back(b);
    left -= 2;
    std::vector<int> free_slots;
    for (int w : {walls[2], walls[3]}) {
      for (int s2 = 0; s2 < 3; ++s2) {
        if (s2 != slot) free_slots.push_back(w * 3 + s2);
      }
    }
    rng.shuffle(free_slots);
    for (int i = 0; i < left && i < static_cast<int>(free_slots.size()); ++i) {
      const int fs = free_slots[static_cast<std::size_t>(i)];
      d.landmarks.push_back(new_landmark(fs / 3, fs % 3, new_pattern(), ""));
    }
  }
}

bool far_from_objects(const Draft& d, double angle_deg, double min_gap_deg) {
  for (const ObjectSpec& o : d.objects) {
    if (circular_gap_deg(o.angle_deg, angle_deg) < min_gap_deg) return false;
  }
  return true;
}

// Places tactile landmarks so that every look-alike pair of places is told apart by touch, with a
// feel-alike pair where the views differ. Uses the report of the layout without objects; false if
// the draw cannot be completed within the option's counts.
bool place_objects(Rng& rng, const GeneratorOptions& o, const RobotGeometry& robot, const AliasReport& layout,
                   const Views& views, const AliasCheckParams& check, Draft& d) {
  const double limit = alike_limit(check);
  d.objects.clear();
  const int max_objects = static_cast<int>(std::lround(o.tactile_landmarks.max));
  const int target = rng.integer(o.tactile_landmarks);
  const double spacing_deg = (2 * kObjectHalfLength + 2 * kReach) * deg_per_m(d, robot);
  const int nshapes = static_cast<int>(object_library().size());
  auto touched_in = [&](const AliasedPlace& p, double widen) {
    std::set<int> s;
    const double span = circular_deg(p.to_deg - p.from_deg) + 2 * widen;
    for (const ObjectSpec& ob : d.objects) {
      if (circular_deg(ob.angle_deg - (p.from_deg - widen)) <= span) s.insert(ob.shape);
    }
    return s;
  };
  const double widen = half_cycle_deg(d.speed, head_radius(d, robot));
  int k = 0;
  auto add = [&](int shape, double angle) {
    d.objects.push_back({shape, circular_deg(angle), std::string(object_library()[static_cast<std::size_t>(shape)].name) + "_" + std::to_string(k++)});
  };
  // A point inside a place, clear of the other objects.
  // A point of a place (widened as touched_in() widens it) clear of the other objects: every free
  // degree is a candidate, one drawn at random.
  auto spot_in = [&](const AliasedPlace& p, double& angle) {
    const double from = p.from_deg - widen;
    const double span = circular_deg(p.to_deg - p.from_deg) + 2 * widen;
    std::vector<double> free;
    for (double a = 0.0; a <= span; a += 1.0) {
      if (far_from_objects(d, from + a, spacing_deg)) free.push_back(from + a);
    }
    if (free.empty()) return false;
    angle = free[static_cast<std::size_t>(rng.integer(0, static_cast<int>(free.size()) - 1))];
    return true;
  };
  // Tell every look-alike pair apart, greedily: an object goes into the place that is in most of
  // the pairs not yet told apart, with a shape none of its partners there has.
  for (int guard = 0; guard <= max_objects; ++guard) {
    std::map<int, int> untold_count;
    std::map<int, std::set<int>> partner_shapes;
    for (const auto& [a, b] : layout.place_pairs) {
      const std::set<int> ta = touched_in(layout.places[static_cast<std::size_t>(a)], widen);
      const std::set<int> tb = touched_in(layout.places[static_cast<std::size_t>(b)], widen);
      if (ta != tb) continue;
      ++untold_count[a];
      ++untold_count[b];
      partner_shapes[a].insert(tb.begin(), tb.end());
      partner_shapes[b].insert(ta.begin(), ta.end());
    }
    if (untold_count.empty()) break;
    if (static_cast<int>(d.objects.size()) >= max_objects) return false;
    // Places by how many untold pairs they are in (ties in random order); the first with room.
    std::vector<std::pair<int, int>> order;  // (-count, place)
    for (const auto& [place, count] : untold_count) order.push_back({-count, place});
    rng.shuffle(order);
    std::stable_sort(order.begin(), order.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    int best = -1;
    double angle = 0.0;
    for (const auto& [neg, place] : order) {
      if (spot_in(layout.places[static_cast<std::size_t>(place)], angle)) {
        best = place;
        break;
      }
    }
    if (best < 0) return false;
    std::vector<int> shapes;
    for (int sh = 0; sh < nshapes; ++sh) {
      if (!partner_shapes[best].count(sh)) shapes.push_back(sh);
    }
    if (shapes.empty()) return false;
    add(shapes[static_cast<std::size_t>(rng.integer(0, static_cast<int>(shapes.size()) - 1))], angle);
  }
  auto premise_kept = [&]() {
    for (const auto& [a, b] : layout.place_pairs) {
      if (touched_in(layout.places[static_cast<std::size_t>(a)], widen) == touched_in(layout.places[static_cast<std::size_t>(b)], widen)) return false;
    }
    return true;
  };
  auto view_distance = [&](double a1, double a2) {
    const int i = views.index_of(a1), j = views.index_of(a2);
    int shift = 0;
    return slam::TemplateStore::visual_distance(views.column_major[static_cast<std::size_t>(i)].data(),
                                                views.column_major[static_cast<std::size_t>(j)].data(), views.w, views.h,
                                                check.match.shift_max, check.match.shift_step, &shift);
  };
  // A feel-alike pair where the views differ: the twin of a placed object (or a new pair).
  for (int tries = 0; tries < 40; ++tries) {
    const int shape = d.objects.empty() ? rng.integer(0, nshapes - 1)
                                        : d.objects[static_cast<std::size_t>(rng.integer(0, static_cast<int>(d.objects.size()) - 1))].shape;
    std::vector<double> at;
    for (const ObjectSpec& ob : d.objects) {
      if (ob.shape == shape) at.push_back(ob.angle_deg);
    }
    const Draft saved = d;
    if (at.empty()) {
      const double a = rng.uniform(0.0, 360.0);
      if (!far_from_objects(d, a, spacing_deg)) continue;
      add(shape, a);
      at.push_back(a);
    }
    const double a = rng.uniform(0.0, 360.0);
    if (!far_from_objects(d, a, spacing_deg) || view_distance(a, at.front()) <= 2 * limit) {
      d = saved;
      continue;
    }
    add(shape, a);
    if (premise_kept() && static_cast<int>(d.objects.size()) <= max_objects) break;
    d = saved;
  }
  // Up to the drawn count, more landmarks of any shape where they keep the premise.
  for (int tries = 0; tries < 40 && static_cast<int>(d.objects.size()) < target; ++tries) {
    const double a = rng.uniform(0.0, 360.0);
    if (!far_from_objects(d, a, spacing_deg)) continue;
    const Draft saved = d;
    add(rng.integer(0, nshapes - 1), a);
    if (!premise_kept()) d = saved;
  }
  std::set<int> shapes;
  for (const ObjectSpec& ob : d.objects) shapes.insert(ob.shape);
  const int min_objects = static_cast<int>(std::lround(o.tactile_landmarks.min));
  return static_cast<int>(d.objects.size()) >= min_objects && static_cast<int>(d.objects.size()) <= max_objects &&
         shapes.size() >= 2;
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char esc[8];
      std::snprintf(esc, sizeof esc, "\\u%04x", static_cast<unsigned char>(c));
      out += esc;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// The header's lines without their "# ", and the parameters to_yaml() writes, with its numbers:
// the world's file and this agree to the digit.
std::string to_json(const std::string& header_text, const Draft& d) {
  std::ostringstream j;
  j << "{\n \"header\": [";
  std::istringstream lines(header_text);
  std::string line;
  for (bool first = true; std::getline(lines, line); first = false) {
    const std::size_t begin = line.find_first_not_of("# ");
    j << (first ? "\n  " : ",\n  ") << json_string(begin == std::string::npos ? "" : line.substr(begin));
  }
  // The east wall's x as written, doubled: the arena's side as the world file gives it.
  const double h = d.side / 2.0;
  const double east_x = std::stod(num(h * std::sqrt(2.0) * std::cos(deg_to_rad(-45.0))));
  j << "\n ],\n \"arena_side\": " << num(2.0 * std::abs(east_x), 3) << ",\n";
  j << " \"landmarks\": " << d.landmarks.size() << ",\n \"tactile_landmarks\": " << d.objects.size()
    << ",\n \"lighting_changes\": " << d.light_changes.size() << ",\n";
  j << " \"trajectory\": {\"type\": \"circle\", \"centre\": [0.0, 0.0], \"radius\": " << num(d.radius, 3)
    << ", \"speed\": " << num(d.speed, 4) << ", \"start_angle_deg\": " << num(d.start_deg, 1)
    << ", \"facing\": \"outwards\", \"direction\": \"" << (d.ccw ? "ccw" : "cw") << "\", \"laps\": " << d.laps
    << "},\n";
  j << " \"camera\": {\"noise_sigma\": " << num(d.camera_noise, 2) << ", \"format\": \"YUYV\"},\n";
  j << " \"odometry\": {\"sigma_v\": " << num(d.sigma_v, 5) << ", \"sigma_omega\": " << num(d.sigma_omega, 5)
    << ", \"bias_vx\": 0.0, \"bias_vy\": " << num(d.bias_vy, 5) << ", \"bias_omega\": " << num(d.bias_omega, 5)
    << ", \"scale_v\": 1.0, \"start_at_truth\": false}\n}\n";
  return j.str();
}

std::string header(const GeneratorOptions& o, const GeneratedWorld& g, const Draft& d) {
  std::ostringstream h;
  h << "# Generated by vita-sim --generate-world --world-seed " << o.world_seed << " --family " << o.family
    << (o.faults ? " --faults" : "") << (o.kidnaps > 0 ? " --kidnaps " + std::to_string(o.kidnaps) : "") << " (draw "
    << g.attempts << ").\n";
  if (!g.rejected.empty()) {
    h << "# Earlier draws failed the check:";
    for (const auto& [why, count] : g.rejected) h << " " << count << " x " << why << ";";
    h << "\n";
  }
  h << "# " << num(d.side, 2) << " m square arena, " << d.landmarks.size() << " wall landmarks, " << d.objects.size()
    << " tactile landmarks; circle r = " << num(d.radius, 3) << " m at " << num(d.speed, 4) << " m/s "
    << (d.ccw ? "ccw" : "cw") << " (lap " << num(2 * kPi * d.radius / d.speed, 1) << " s), " << d.laps << " laps.\n";
  h << "# Checked with the renderer and slamd's visual template (noise-free views every few degrees of the path):\n";
  h << "# look-alike places (polar angles of the path, deg) and what the whiskers touch there:\n";
  for (std::size_t i = 0; i < g.report.place_pairs.size(); ++i) {
    const auto& [a, b] = g.report.place_pairs[i];
    const AliasedPlace& pa = g.report.places[static_cast<std::size_t>(a)];
    const AliasedPlace& pb = g.report.places[static_cast<std::size_t>(b)];
    auto touched = [](const AliasedPlace& p) {
      std::string s;
      for (const std::string& t : p.touched) s += (s.empty() ? "" : "+") + t;
      return s.empty() ? std::string("nothing") : s;
    };
    const bool untold = std::find(g.report.untold_pairs.begin(), g.report.untold_pairs.end(), g.report.place_pairs[i]) !=
                        g.report.untold_pairs.end();
    h << "#   " << num(pa.from_deg, 0) << "-" << num(pa.to_deg, 0) << " ~ " << num(pb.from_deg, 0) << "-"
      << num(pb.to_deg, 0) << " (closest views " << num(g.report.pairs[i].angle_a_deg, 0) << "/"
      << num(g.report.pairs[i].angle_b_deg, 0) << ", distance " << num(g.report.pairs[i].distance, 4)
      << "): touch " << touched(pa) << " vs " << touched(pb) << (untold ? "  <- NOT told apart by touch" : "") << "\n";
  }
  if (!g.report.featureless.empty()) {
    h << "# featureless stretches (a view alike with the same stretch's, shifted along it; only odometry tells\n"
         "# where along it the robot is, so no landmark is placed for them):";
    for (const auto& [a, b] : g.report.featureless) {
      const AliasedPlace& pa = g.report.places[static_cast<std::size_t>(a)];
      const AliasedPlace& pb = g.report.places[static_cast<std::size_t>(b)];
      h << " " << num(std::min(pa.from_deg, pb.from_deg), 0) << "-" << num(std::max(pa.to_deg, pb.to_deg), 0);
    }
    h << "\n";
  }
  h << "# feel-alike tactile landmarks where the views differ:";
  for (const auto& [a, b] : g.report.feel_alike_pairs_apart) h << " " << a << "~" << b;
  h << (g.report.feel_alike_pairs_apart.empty() ? " none\n" : "\n");
  if (!d.stress_note.empty()) h << "# stress: " << d.stress_note << "\n";
  h << "# Format: docs/simulator.md. Rerun: vita-sim --world THIS_FILE --output run.lcmlog\n";
  return h.str();
}

}  // namespace

namespace {

// Throws GeneratorOptionError if no draw of `o` can fit: its best case, the smallest trajectory in
// the largest arena, must hold the head's path and outside it the tactile landmarks (the gap, the
// deepest shape) and the whiskers' reach inside the walls. Each draw renders and matches a lap of
// views (seconds): an impossible request is said at once, not after every draw has failed.
void check_fits(const GeneratorOptions& o, const RobotGeometry& robot) {
  double deepest = 0.0;  // radially, of any tactile landmark
  for (const ObjectShape& s : object_library()) {
    if (s.circle) deepest = std::max(deepest, 2.0 * s.radius);
    for (const auto& [x, y] : s.points) deepest = std::max(deepest, x);
  }
  const double head_r = head_path_radius(o.radius.min, robot);
  const double needs = head_r + std::max(kMinGap + deepest, kReach);
  if (needs >= o.side.max / 2.0) {
    throw GeneratorOptionError("--radius " + num(o.radius.min, 3) + ".." + num(o.radius.max, 3) + " in --arena-side " +
                               num(o.side.min, 3) + ".." + num(o.side.max, 3) + ": no world fits (the head's path at " +
                               num(head_r, 3) + " m and what stands outside it need " + num(needs, 3) +
                               " m from the centre, the largest arena has " + num(o.side.max / 2.0, 3) + " m to its walls)");
  }
}

}  // namespace

GeneratedWorld generate_world(const GeneratorOptions& o, const RobotGeometry& robot, const AliasCheckParams& check) {
  validate(o);
  check_fits(o, robot);
  // One stream per seed; each draw continues it, so a seed's world does not depend on the machine.
  Rng rng(o.world_seed * 0x2545F4914F6CDD1Dull + 0x5851F42D4C957F2Dull);
  GeneratedWorld g;
  std::string last_failure = "no draw made";
  auto reject = [&](const std::string& why) {
    last_failure = why;
    ++g.rejected[why];
  };
  for (g.attempts = 1; g.attempts <= o.max_attempts; ++g.attempts) {
    Draft d;
    draw_layout(rng, o, d);
    d.name = "generated_" + o.family + "_" + std::to_string(o.world_seed);
    d.objects.clear();
    const World bare = load_yaml(to_yaml(d, robot));
    const AliasReport layout = check_aliasing(bare, robot, check);
    if (layout.place_pairs.size() < 2) {
      reject("fewer than two look-alike pairs of places");
      continue;
    }
    const Views views = render_views(bare, robot, check);
    bool placed = false;
    for (int p = 0; p < 30 && !placed; ++p) placed = place_objects(rng, o, robot, layout, views, check, d);
    if (!placed) {
      reject("no placement of tactile landmarks tells every look-alike pair apart");
      continue;
    }
    // Check the world as written: tactile landmarks change the views a little, and the touch is
    // measured with the whisker geometry, not assumed.
    World world = load_yaml(to_yaml(d, robot));
    AliasReport report = check_aliasing(world, robot, check);
    if (!report.premise_holds()) {
      reject(report.untold_pairs.empty() ? "as written: no feel-alike pair where the views differ, or < 2 look-alike pairs"
                                         : "as written: a look-alike pair is not told apart by touch");
      continue;
    }
    if (o.family == "stress") {
      // Break the premise at one look-alike pair: remove what is touched at both places.
      const auto& [a, b] = report.place_pairs[static_cast<std::size_t>(rng.integer(0, static_cast<int>(report.place_pairs.size()) - 1))];
      const AliasedPlace pa = report.places[static_cast<std::size_t>(a)];
      const AliasedPlace pb = report.places[static_cast<std::size_t>(b)];
      const double widen = half_cycle_deg(d.speed, head_radius(d, robot)) + (kObjectHalfLength + kReach) * deg_per_m(d, robot);
      auto near = [&](const AliasedPlace& p, double ang) {
        return circular_deg(ang - (p.from_deg - widen)) <= circular_deg(p.to_deg - p.from_deg) + 2 * widen;
      };
      std::vector<ObjectSpec> kept;
      for (const ObjectSpec& ob : d.objects) {
        if (!near(pa, ob.angle_deg) && !near(pb, ob.angle_deg)) kept.push_back(ob);
      }
      d.objects = kept;
      d.stress_note = "premise broken on purpose: nothing to touch at the look-alike places " + num(pa.from_deg, 0) +
                      "-" + num(pa.to_deg, 0) + " and " + num(pb.from_deg, 0) + "-" + num(pb.to_deg, 0) + " deg";
      world = load_yaml(to_yaml(d, robot));
      report = check_aliasing(world, robot, check);
    }
    if (o.faults) d.faults_yaml = draw_faults(rng, d.laps * 2.0 * kPi * d.radius / d.speed);
    if (o.kidnaps > 0) d.faults_yaml = (o.faults ? d.faults_yaml : "  faults:\n") + draw_kidnaps(rng, d, o.kidnaps);
    g.report = report;
    const std::string body = to_yaml(d, robot);
    const std::string head = header(o, g, d);
    g.yaml = head + body;
    g.json = to_json(head, d);
    g.world = load_yaml(body);
    return g;
  }
  throw std::runtime_error("no world of family '" + o.family + "' passed the check in " + std::to_string(o.max_attempts) +
                           " draws (last: " + last_failure + ")");
}

}  // namespace whiskeye::sim
