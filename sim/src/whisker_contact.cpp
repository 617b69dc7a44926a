// Swept whisker/world intersection (see whisker_contact.h).
#include "whiskeye/sim/whisker_contact.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace whiskeye::sim {

namespace {

struct Candidate {
  const Solid* solid = nullptr;
  const Panel* panel = nullptr;
  int solid_index = -1;
};

// The whisker in the world at one protraction angle.
struct Ray {
  Point2 o;        // base, world xy
  double zb = 0;   // base height above the floor
  double tan_el = 0;
  double reach = 0;  // horizontal length
};

double point_segment_distance(const Point2& p, const Point2& a, const Point2& b) {
  const double ex = b.x - a.x;
  const double ey = b.y - a.y;
  const double len2 = ex * ex + ey * ey;
  double u = len2 > 0.0 ? ((p.x - a.x) * ex + (p.y - a.y) * ey) / len2 : 0.0;
  u = std::clamp(u, 0.0, 1.0);
  return std::hypot(p.x - a.x - u * ex, p.y - a.y - u * ey);
}

// Horizontal distances [lo, hi] at which the whisker's height is inside [z0, z1].
bool height_window(const Ray& ray, double z0, double z1, double& lo, double& hi) {
  if (std::abs(ray.tan_el) < 1e-12) {
    if (ray.zb < z0 || ray.zb > z1) return false;
    lo = 0.0;
    hi = std::numeric_limits<double>::infinity();
    return true;
  }
  const double a = (z0 - ray.zb) / ray.tan_el;
  const double b = (z1 - ray.zb) / ray.tan_el;
  lo = std::min(a, b);
  hi = std::max(a, b);
  return true;
}

// Nearest horizontal distance at which the whisker at azimuth `az` meets a candidate; +inf if none.
double first_hit(const Ray& ray, double az, const std::vector<Candidate>& cands, int& which,
                 std::vector<SolidHit>& scratch) {
  const Point2 d{std::cos(az), std::sin(az)};
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < cands.size(); ++i) {
    const Candidate& c = cands[i];
    double zlo;
    double zhi;
    if (c.panel) {
      double t;
      double s;
      if (!height_window(ray, c.panel->z0, c.panel->z1, zlo, zhi)) continue;
      if (ray_panel(ray.o, d, *c.panel, t, s) && t <= ray.reach && t >= zlo && t <= zhi && t < best) {
        best = t;
        which = static_cast<int>(i);
      }
      continue;
    }
    if (!height_window(ray, c.solid->z0, c.solid->z1, zlo, zhi)) continue;
    scratch.clear();
    ray_solid(ray.o, d, *c.solid, scratch);
    for (const SolidHit& h : scratch) {
      const double lo = std::max({h.t_in, zlo, 0.0});
      const double hi = std::min({h.t_out, zhi, ray.reach});
      if (lo <= hi && lo < best) {
        best = lo;
        which = static_cast<int>(i);
      }
    }
  }
  return best;
}

}  // namespace

std::optional<WhiskerContact> find_whisker_contact(const World& world, const RobotGeometry& robot,
                                                   const Pose2& T_world_head, int w,
                                                   const SweepParams& sweep) {
  const WhiskerGeometry& g = robot.whiskers[static_cast<std::size_t>(w)];
  Ray ray;
  transform_point(T_world_head, g.p_base_in_head.x, g.p_base_in_head.y, ray.o.x, ray.o.y);
  ray.zb = robot.head_height + g.p_base_in_head.z;
  const double cos_el = std::cos(g.elevation);
  ray.tan_el = std::tan(g.elevation);
  ray.reach = g.length * cos_el;
  const double z_lo = ray.zb + std::min(0.0, ray.reach * ray.tan_el);
  const double z_hi = ray.zb + std::max(0.0, ray.reach * ray.tan_el);

  // Only what the whisker can reach at any angle: most of the time nothing, and the sweep is skipped.
  std::vector<Candidate> cands;
  for (std::size_t i = 0; i < world.solids.size(); ++i) {
    const Solid& s = world.solids[i];
    if (s.z1 < z_lo || s.z0 > z_hi) continue;
    if (std::hypot(s.centre.x - ray.o.x, s.centre.y - ray.o.y) - s.radius > ray.reach) continue;
    cands.push_back({&s, nullptr, static_cast<int>(i)});
  }
  for (const auto* panels : {&world.walls, &world.landmarks}) {
    for (const Panel& p : *panels) {
      if (p.z1 < z_lo || p.z0 > z_hi) continue;
      if (point_segment_distance(ray.o, p.from, p.to) > ray.reach) continue;
      cands.push_back({nullptr, &p, -1});
    }
  }
  if (cands.empty()) return std::nullopt;

  std::vector<SolidHit> scratch;
  auto azimuth = [&](double theta) { return T_world_head.theta + g.azimuth0 - g.side * theta; };
  int which = -1;
  double t_hit = first_hit(ray, azimuth(sweep.theta_lo), cands, which, scratch);
  double theta_hit = sweep.theta_lo;
  if (!std::isfinite(t_hit)) {
    double prev = sweep.theta_lo;
    bool found = false;
    for (double th = sweep.theta_lo + sweep.step; prev < sweep.theta_hi; th += sweep.step) {
      th = std::min(th, sweep.theta_hi);
      if (std::isfinite(first_hit(ray, azimuth(th), cands, which, scratch))) {
        double lo = prev;
        double hi = th;
        for (int i = 0; i < sweep.bisections; ++i) {
          const double mid = 0.5 * (lo + hi);
          int wm = -1;
          if (std::isfinite(first_hit(ray, azimuth(mid), cands, wm, scratch))) {
            hi = mid;
          } else {
            lo = mid;
          }
        }
        theta_hit = hi;
        t_hit = first_hit(ray, azimuth(hi), cands, which, scratch);
        found = std::isfinite(t_hit);
        break;
      }
      prev = th;
    }
    if (!found) return std::nullopt;
  }
  WhiskerContact c;
  c.theta = theta_hit;
  c.radial = t_hit / cos_el;
  c.p_contact_in_head = robot.whisker_point(w, theta_hit, c.radial);
  const Candidate& hit = cands[static_cast<std::size_t>(which)];
  c.solid = hit.solid_index;
  c.stiffness = hit.solid ? hit.solid->stiffness : 1.0;
  return c;
}

}  // namespace whiskeye::sim
