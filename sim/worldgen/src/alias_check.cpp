// The aliasing check of a world (see alias_check.h).
#include "whiskeye/sim/alias_check.h"

#include "path_views.h"
#include "whiskeye/sim/renderer.h"
#include "whiskeye/sim/whisker_contact.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

namespace whiskeye::sim {

namespace worldgen {

Pose2 pose_at_angle(const Trajectory& trajectory, double deg) {
  Trajectory t = trajectory;
  t.start_angle = deg_to_rad(deg);
  return t.pose_at(0.0);
}

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

}  // namespace worldgen

namespace {

using namespace worldgen;

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
  const double widen_deg = half_cycle_deg(p.whisking, t.speed, head_r) + p.angle_step_deg / 2;
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

}  // namespace whiskeye::sim
