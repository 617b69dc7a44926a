// The drafting of a generated world (see world_draft.h).
#include "world_draft.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace whiskeye::sim::worldgen {

namespace {

using Decimal = WorldWriter::Decimal;
using Entry = WorldWriter::Entry;

// A wall landmark pattern, drawn; `k` makes the name unique.
PatternSpec draw_pattern(Rng& rng, int k) {
  PatternSpec p;
  p.name = "p";  // appended, not "p" + std::string: GCC 12 -O3 -Wrestrict (bug 105329)
  p.name += std::to_string(k);
  const double low = rng.uniform(0.05, 0.2);
  const double high = rng.uniform(0.8, 0.95);
  const Entry low_high{{"low", Decimal{low, 2}}, {"high", Decimal{high, 2}}};
  switch (rng.integer(0, 4)) {
    case 0:
      p.name += "_vstripes";
      p.fields = {{"type", "stripes"}, {"orientation", "vertical"}, {"period", Decimal{rng.uniform(0.14, 0.34), 3}},
                  {"duty", Decimal{0.5, 1}}};
      break;
    case 1:
      p.name += "_hstripes";
      p.fields = {{"type", "stripes"}, {"orientation", "horizontal"}, {"period", Decimal{rng.uniform(0.12, 0.26), 3}},
                  {"duty", Decimal{0.5, 1}}};
      break;
    case 2:
      p.name += "_checker";
      p.fields = {{"type", "checker"}, {"cell", Decimal{rng.uniform(0.14, 0.3), 3}}};
      break;
    case 3: {
      p.name += "_blobs";
      // Drawn from the last field written to the first: the order every generated world was made in.
      const int64_t seed = rng.integer(1, 9999);
      const double radius = rng.uniform(0.07, 0.1);
      const int64_t count = rng.integer(4, 6);
      const double period = rng.uniform(0.5, 0.7);
      p.fields = {{"type", "blobs"}, {"period", Decimal{period, 3}}, {"count", count}, {"radius", Decimal{radius, 3}},
                  {"seed", seed}};
      break;
    }
    default:
      p.name += "_dark";
      p.fields = {{"type", "solid"}, {"high", Decimal{rng.uniform(0.08, 0.2), 2}}};
      return p;
  }
  p.fields.insert(p.fields.end(), low_high.begin(), low_high.end());
  return p;
}

WorldWriter::Scalars xy(double x, double y, int decimals = 4) { return {Decimal{x, decimals}, Decimal{y, decimals}}; }

}  // namespace

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


double head_radius(const Draft& d, const RobotGeometry& robot) { return head_path_radius(d.radius, robot); }

double deg_per_m(const Draft& d, const RobotGeometry& robot) { return 180.0 / (kPi * head_radius(d, robot)); }

std::string write_world(const Draft& d, const RobotGeometry& robot, const std::string& comment) {
  const double h = d.side / 2.0;
  WorldWriter y(comment +
                "Visual landmarks: from -> to runs left to right as seen from the centre, so landmarks alike on two\n"
                "walls look alike from the two places that face them.\n"
                "Tactile landmarks: shape frames, x radially outwards from the path, y along it; the near face " +
                format_decimal(d.gap, 3) + " m\noutside the head's path.");
  y.scalar("name", d.name);
  y.scalar("floor_value", Decimal{d.floor, 2});
  y.scalar("sky_value", Decimal{0.85, 2});
  y.scalar("wall_height", Decimal{1.2, 1});
  std::vector<Entry> patterns;
  for (const PatternSpec& p : d.patterns) {
    Entry e{{"name", p.name}};
    e.insert(e.end(), p.fields.begin(), p.fields.end());
    patterns.push_back(std::move(e));
  }
  y.list("patterns", patterns);
  std::vector<Entry> walls;
  const char* wall_names[4] = {"east", "north", "west", "south"};
  for (int w = 0; w < 4; ++w) {
    // Corners counter-clockwise: east wall from (h, -h) to (h, h), and so on.
    const double a0 = deg_to_rad(90.0 * w - 45.0);
    const double a1 = deg_to_rad(90.0 * w + 45.0);
    const double r = h * std::sqrt(2.0);
    walls.push_back({{"name", wall_names[w]},
                     {"from", xy(r * std::cos(a0), r * std::sin(a0))},
                     {"to", xy(r * std::cos(a1), r * std::sin(a1))},
                     {"pattern", d.patterns[0].name}});
  }
  y.list("walls", walls);
  std::vector<Entry> landmarks;
  for (const LandmarkSpec& l : d.landmarks) {
    const double alpha = deg_to_rad(90.0 * l.wall);
    const double nx = std::cos(alpha), ny = std::sin(alpha);  // outward normal
    const double rx = std::sin(alpha), ry = -std::cos(alpha);  // "right" seen from the centre
    const double off = -h * std::tan(deg_to_rad(kSlotDeg[l.slot]));  // along "right"
    const double cx = nx * h + rx * off, cy = ny * h + ry * off;
    landmarks.push_back({{"name", l.name},
                         {"from", xy(cx - rx * l.width / 2, cy - ry * l.width / 2)},
                         {"to", xy(cx + rx * l.width / 2, cy + ry * l.width / 2)},
                         {"z", xy(l.z0, l.z1, 3)},
                         {"pattern", d.patterns[static_cast<std::size_t>(l.pattern)].name}});
  }
  y.list("visual_landmarks", landmarks);
  std::vector<Entry> objects;
  const double r0 = head_radius(d, robot) + d.gap;
  for (const ObjectSpec& o : d.objects) {
    const ObjectShape& s = object_library()[static_cast<std::size_t>(o.shape)];
    const double a = deg_to_rad(o.angle_deg);
    const double r = s.circle ? r0 + s.radius : r0;
    Entry e{{"name", o.name},
            {"shape", s.circle ? "circle" : "polygon"},
            {"pose", WorldWriter::Scalars{Decimal{r * std::cos(a), 4}, Decimal{r * std::sin(a), 4}, Decimal{o.angle_deg, 3}}}};
    if (s.circle) {
      e.push_back({"radius", Decimal{s.radius, 3}});
    } else {
      std::vector<WorldWriter::Scalars> points;
      for (const auto& [px, py] : s.points) points.push_back(xy(px, py, 3));
      e.push_back({"points", points});
    }
    e.push_back({"z", WorldWriter::Scalars{Decimal{0.0, 1}, Decimal{0.31, 2}}});
    e.push_back({"pattern", "object"});
    e.push_back({"top_value", Decimal{0.6, 1}});
    objects.push_back(std::move(e));
  }
  y.list("tactile_landmarks", objects);
  y.begin_section("lighting");
  y.scalar("brightness", Decimal{1.0, 1});
  y.scalar("ambient", Decimal{0.6, 1});
  y.scalar("attenuation", Decimal{0.05, 2});
  std::vector<Entry> changes;
  for (const LightChange& c : d.light_changes) {
    changes.push_back({{"start", Decimal{c.start, 1}}, {"duration", Decimal{c.duration, 2}}, {"gain", Decimal{c.gain, 2}}});
  }
  y.flow_list("changes", changes);
  y.end_section();
  y.entry("trajectory", {{"type", "circle"},
                         {"centre", xy(0.0, 0.0, 1)},
                         {"radius", Decimal{d.radius, 3}},
                         {"speed", Decimal{d.speed, 4}},
                         {"start_angle_deg", Decimal{d.start_deg, 1}},
                         {"facing", "outwards"},
                         {"direction", d.ccw ? "ccw" : "cw"},
                         {"laps", int64_t{d.laps}}});
  y.entry("camera", {{"noise_sigma", Decimal{d.camera_noise, 2}}, {"format", "YUYV"}});
  y.entry("odometry", {{"sigma_v", Decimal{d.sigma_v, 5}},
                       {"sigma_omega", Decimal{d.sigma_omega, 5}},
                       {"bias_vx", Decimal{0.0, 1}},
                       {"bias_vy", Decimal{d.bias_vy, 5}},
                       {"bias_omega", Decimal{d.bias_omega, 5}},
                       {"scale_v", Decimal{1.0, 1}},
                       {"start_at_truth", false}});
  if (!d.faults.empty() || !d.kidnaps.empty()) {
    y.begin_section("faults");
    for (const FaultSpec& f : d.faults) {
      WorldWriter::Scalars dead;
      for (const int w : f.dead_whiskers) dead.push_back(int64_t{w});
      y.scalars("dead_whiskers", dead);
      y.flow_list("board_offline", {{{"board", int64_t{f.offline_board}},
                                     {"start", Decimal{f.offline_start, 1}},
                                     {"duration", Decimal{30.0, 1}}}});
      y.flow_list("camera_blackout", {{{"start", Decimal{f.blackout_start, 1}}, {"duration", Decimal{10.0, 1}}}});
      y.flow_list("odometry_slip", {{{"start", Decimal{f.slip_start, 1}},
                                     {"duration", Decimal{10.0, 1}},
                                     {"scale", Decimal{f.slip_faster ? 1.2 : 0.8, 1}}}});
    }
    if (!d.kidnaps.empty()) {
      std::vector<Entry> kidnaps;
      for (const KidnapSpec& k : d.kidnaps) kidnaps.push_back({{"at", Decimal{k.at, 1}}, {"to_angle", Decimal{k.to_angle, 4}}});
      y.flow_list("kidnap", kidnaps);
    }
    y.end_section();
  }
  return y.text();
}

FaultSpec draw_faults(Rng& rng, double duration) {
  FaultSpec f;
  std::vector<int> whiskers(kNumWhiskers);
  for (int w = 0; w < kNumWhiskers; ++w) whiskers[static_cast<std::size_t>(w)] = w;
  rng.shuffle(whiskers);
  f.dead_whiskers.assign(whiskers.begin(), whiskers.begin() + 4);
  std::sort(f.dead_whiskers.begin(), f.dead_whiskers.end());
  auto start = [&](double length) { return rng.uniform(0.15 * duration, std::max(0.15 * duration, 0.9 * duration - length)); };
  f.offline_board = rng.integer(0, kNumBoards - 1);
  f.offline_start = start(30.0);
  f.blackout_start = start(10.0);
  f.slip_start = start(10.0);
  f.slip_faster = rng.chance(0.5);
  return f;
}

// Kidnaps after the first lap (the place has been mapped): the rest of the run is shared out, and
// each kidnap is followed by at least a lap before the next one and the end where the run is long
// enough (else by half its share); each to a point of the path 90-270 deg of polar angle from where
// the robot is then. Times and angles are rounded as written, so the file says what was drawn.
std::vector<KidnapSpec> draw_kidnaps(Rng& rng, const Draft& d, int n) {
  const double lap = 2.0 * kPi * d.radius / d.speed;
  const double share = (d.laps - 1) * lap / n;
  const double slack = share >= lap + 0.2 ? share - lap - 0.2 : 0.5 * share;
  const double sign = d.ccw ? 1.0 : -1.0;
  double t_prev = 0.0;
  double angle_prev = deg_to_rad(d.start_deg);
  std::vector<KidnapSpec> out;
  for (int i = 0; i < n; ++i) {
    const double t = std::ceil((lap + i * share + rng.uniform(0.0, slack)) * 10.0) / 10.0;
    const double here = angle_prev + sign * d.speed * (t - t_prev) / d.radius;
    const double to = std::round(wrap_angle(here + deg_to_rad(rng.uniform(90.0, 270.0))) * 1e4) / 1e4;
    out.push_back({t, to});
    t_prev = t;
    angle_prev = to;
  }
  return out;
}

void draw_layout(Rng& rng, const GeneratorOptions& o, Draft& d) {
  d = Draft{};
  d.side = rng.uniform(o.side);
  d.wall_grey = rng.uniform(0.5, 0.6);
  d.floor = rng.uniform(0.25, 0.35);
  d.patterns.push_back({"wall", {{"type", "solid"}, {"high", Decimal{d.wall_grey, 2}}}});
  d.patterns.push_back({"object",
                        {{"type", "stripes"}, {"orientation", "horizontal"}, {"period", Decimal{0.08, 2}},
                         {"duty", Decimal{0.5, 1}}, {"low", Decimal{0.25, 2}}, {"high", Decimal{0.40, 2}}}});
  d.radius = rng.uniform(o.radius);
  d.speed = rng.uniform(o.speed);
  d.start_deg = rng.uniform(0.0, 360.0);
  d.ccw = rng.chance(0.5);
  d.laps = rng.integer(o.laps);
  const double bias = rng.uniform(o.odometry_bias_scale);
  const double noise = rng.uniform(o.odometry_noise_scale);
  d.bias_vy = 0.002 * bias * (rng.chance(0.5) ? 1.0 : -1.0);
  // One draw a statement: the operands of * are unsequenced, and compilers order the calls differently.
  const double bias_omega = rng.uniform(o.odometry_bias_scale);
  d.bias_omega = 0.002 * bias_omega * (rng.chance(0.5) ? 1.0 : -1.0);
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

namespace {

bool far_from_objects(const Draft& d, double angle_deg, double min_gap_deg) {
  for (const ObjectSpec& o : d.objects) {
    if (circular_gap_deg(o.angle_deg, angle_deg) < min_gap_deg) return false;
  }
  return true;
}

}  // namespace

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
  const double widen = half_cycle_deg(check.whisking, d.speed, head_radius(d, robot));
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

}  // namespace whiskeye::sim::worldgen
