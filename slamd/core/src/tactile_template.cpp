// Tactile template: contact estimation from θ and deflection, PFH and SDA. See tactile_template.h
// for the model; docs/slam-core.md for why it differs from the original ViTa-SLAM code.
#include "whiskeye/slam/tactile_template.h"

#include <Eigen/Dense>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <utility>

namespace whiskeye::slam {

void load(const ParamNode& n, TactileParams& p) {
  n.get("contact_threshold", p.contact_threshold, 0.0, 1e6);
  n.get("min_contact_samples", p.min_contact_samples, 1, 100000);
  n.get("use_contact_flags", p.use_contact_flags);
  n.get("speed_gain", p.speed_gain, -1.0, 1.0);
  n.get("min_theta_span", p.min_theta_span, 0.0, 1.0);
  n.get("fallback_radius_fraction", p.fallback_radius_fraction, 0.01, 1.0);
  std::string kind = p.pfh == PfhKind::Rusu ? "rusu" : "histogram";
  n.get("pfh", kind);
  if (kind == "rusu") {
    p.pfh = PfhKind::Rusu;
  } else if (kind == "histogram") {
    p.pfh = PfhKind::Histogram;
  } else {
    throw ParamError(n.source() + ": '" + n.path_of("pfh") + "' = \"" + kind + "\" must be \"rusu\" or \"histogram\"");
  }
  n.get("normal_neighbours", p.normal_neighbours, 3, kNumWhiskers);
  std::vector<double> lo(p.histogram_min.begin(), p.histogram_min.end());
  std::vector<double> hi(p.histogram_max.begin(), p.histogram_max.end());
  n.get("histogram_min", lo);
  n.get("histogram_max", hi);
  if (lo.size() != 3 || hi.size() != 3) {
    throw ParamError(n.source() + ": '" + n.path_of("histogram_min") + "' and 'histogram_max' must be [x, y, z]");
  }
  for (int i = 0; i < 3; ++i) {
    if (!(hi[static_cast<size_t>(i)] > lo[static_cast<size_t>(i)])) {
      throw ParamError(n.source() + ": '" + n.path_of("histogram_max") + "' must exceed histogram_min on every axis");
    }
    p.histogram_min[static_cast<size_t>(i)] = lo[static_cast<size_t>(i)];
    p.histogram_max[static_cast<size_t>(i)] = hi[static_cast<size_t>(i)];
  }
}

namespace {

struct WhiskerTrace {
  std::vector<double> theta;
  std::vector<double> magnitude;
  std::vector<int64_t> utime;
};

using WhiskerTraces = std::array<WhiskerTrace, kNumWhiskers>;

// Which whiskers a sample measured (bit w: valid, and whisker w's three values finite).
uint32_t measured(const WhiskSample& s) {
  if (!s.valid) return 0;
  uint32_t m = 0;
  for (size_t w = 0; w < static_cast<size_t>(kNumWhiskers); ++w) {
    const bool ok = std::isfinite(s.theta[w]) && std::isfinite(s.deflection_x[w]) && std::isfinite(s.deflection_y[w]);
    m |= static_cast<uint32_t>(ok) << w;
  }
  return m;
}

// The per-sample arithmetic of a whisker's contact, shared by both paths below so that they agree
// to the bit. The x deflection is first corrected for the whisking-speed term (drag/inertia bends a
// moving whisker against its motion: x −= −speed_gain·θ̇), with θ̇ from central differences of the
// valid samples: sample k's neighbours are k − 1 and k + 1, itself at either end.
std::pair<size_t, size_t> neighbours(size_t k, size_t n) { return {k == 0 ? 0 : k - 1, k + 1 < n ? k + 1 : k}; }

// θ̇ of whisker w between the samples a and b; 0 when they are the same moment (or out of order).
double theta_rate(const WhiskSample& a, const WhiskSample& b, size_t w) {
  const double dt = static_cast<double>(b.utime - a.utime) * 1e-6;
  return dt > 0.0 ? (static_cast<double>(b.theta[w]) - a.theta[w]) / dt : 0.0;
}

double corrected_dx(const WhiskSample& s, size_t w, double speed_gain, double theta_dot) {
  return s.deflection_x[w] + speed_gain * theta_dot;
}

// False for most samples, far below the threshold: hypot(dx, dy) ≤ √2·max(|dx|, |dy|) (to within an
// ulp) < 1.5·max, so this skips them exactly as add_if_contact's test would, without the libm call.
bool may_exceed(double dx, double dy, double threshold) { return !(1.5 * std::max(std::abs(dx), std::abs(dy)) <= threshold); }

// Sample s of whisker w joins its trace when its deflection's magnitude exceeds the threshold (and,
// with use_contact_flags, its contact flag is set).
void add_if_contact(WhiskerTrace& t, const WhiskSample& s, size_t w, double dx, const TactileParams& p) {
  const double m = std::hypot(dx, static_cast<double>(s.deflection_y[w]));
  if (m <= p.contact_threshold) return;
  if (p.use_contact_flags && !s.contact[w]) return;
  t.theta.push_back(s.theta[w]);
  t.magnitude.push_back(m);
  t.utime.push_back(s.utime);
}

// The samples of whisker w that count as contact. `masks`: measured() of every sample; `valid`: a
// buffer for the whisker's valid samples.
WhiskerTrace contact_samples(const WhiskCycleInput& cycle, size_t w, const TactileParams& p,
                             const std::vector<uint32_t>& masks, std::vector<const WhiskSample*>& valid) {
  WhiskerTrace t;
  valid.clear();
  for (size_t k = 0; k < cycle.samples.size(); ++k) {
    if ((masks[k] >> w) & 1u) valid.push_back(&cycle.samples[k]);
  }
  const size_t n = valid.size();
  for (size_t k = 0; k < n; ++k) {
    const WhiskSample& s = *valid[k];
    double theta_dot = 0.0;
    if (p.speed_gain != 0.0 && n > 1) {
      const auto [a, b] = neighbours(k, n);
      theta_dot = theta_rate(*valid[a], *valid[b], w);
    }
    const double dx = corrected_dx(s, w, p.speed_gain, theta_dot);
    if (may_exceed(dx, s.deflection_y[w], p.contact_threshold)) add_if_contact(t, s, w, dx, p);
  }
  return t;
}

// contact_samples for every whisker of a cycle whose every sample measured every whisker (the
// usual one): a whisker's valid samples are then all of them, so a sample's neighbours are the same
// for all whiskers, and each sample's whiskers are computed side by side (vectorised); only those
// above the cheap bound go on, whisker by whisker.
WhiskerTraces contact_traces_all_measured(const WhiskCycleInput& cycle, const TactileParams& p) {
  WhiskerTraces traces;
  const std::vector<WhiskSample>& samples = cycle.samples;
  const size_t n = samples.size();
  std::array<double, kNumWhiskers> dx{};
  for (size_t k = 0; k < n; ++k) {
    const WhiskSample& s = samples[k];
    if (p.speed_gain != 0.0 && n > 1) {
      const auto [a, b] = neighbours(k, n);
      for (size_t w = 0; w < static_cast<size_t>(kNumWhiskers); ++w) {
        dx[w] = corrected_dx(s, w, p.speed_gain, theta_rate(samples[a], samples[b], w));
      }
    } else {
      for (size_t w = 0; w < static_cast<size_t>(kNumWhiskers); ++w) dx[w] = corrected_dx(s, w, p.speed_gain, 0.0);
    }
    uint32_t above = 0;  // bit w: may_exceed
    for (size_t w = 0; w < static_cast<size_t>(kNumWhiskers); ++w) {
      above |= static_cast<uint32_t>(may_exceed(dx[w], s.deflection_y[w], p.contact_threshold)) << w;
    }
    for (; above != 0; above &= above - 1) {
      const auto w = static_cast<size_t>(std::countr_zero(above));
      add_if_contact(traces[w], s, w, dx[w], p);
    }
  }
  return traces;
}

// Every whisker's contact samples: what both the contact estimates and the SDA read. `sensed`, when
// given: the whiskers some sample measured (bit w).
WhiskerTraces contact_traces(const WhiskCycleInput& cycle, const TactileParams& p, uint32_t* sensed = nullptr) {
  constexpr uint32_t kEvery = (1u << kNumWhiskers) - 1;
  std::vector<uint32_t> masks(cycle.samples.size());
  uint32_t any = 0, all = kEvery;
  for (size_t k = 0; k < masks.size(); ++k) {
    masks[k] = measured(cycle.samples[k]);
    any |= masks[k];
    all &= masks[k];
  }
  if (sensed != nullptr) *sensed = any;
  WhiskerTraces traces;
  if (all == kEvery) {
    traces = contact_traces_all_measured(cycle, p);
  } else {
    std::vector<const WhiskSample*> valid;
    valid.reserve(cycle.samples.size());
    for (size_t w = 0; w < static_cast<size_t>(kNumWhiskers); ++w) traces[w] = contact_samples(cycle, w, p, masks, valid);
  }
  // A whisker with fewer contact samples than min_contact_samples touched nothing.
  for (WhiskerTrace& t : traces) {
    if (static_cast<int>(t.theta.size()) < p.min_contact_samples) t = {};
  }
  return traces;
}

int bin_of(double v, double lo, double hi) {
  const int b = static_cast<int>(std::floor((v - lo) / (hi - lo) * kPfhBinsPerDim));
  return std::clamp(b, 0, kPfhBinsPerDim - 1);
}

}  // namespace

namespace {

std::vector<ContactEstimate> estimate_contacts(const WhiskerTraces& traces, const RobotGeometry& geometry,
                                               const TactileParams& p) {
  std::vector<ContactEstimate> out;
  for (int w = 0; w < kNumWhiskers; ++w) {
    const WhiskerTrace& t = traces[static_cast<size_t>(w)];
    if (t.theta.empty()) continue;
    const WhiskerGeometry& g = geometry.whiskers[static_cast<size_t>(w)];
    ContactEstimate c;
    c.whisker = w;
    // Least squares |d| = a + k·θ over the rising part of the contact — from the first contact
    // sample to the sample of maximum deflection — where the whisker is being pushed into a contact
    // point that is still where it was touched; θ_c is where the line crosses zero. (Later samples
    // mix in the RCP hold, the retraction and the robot's own motion, which moves the contact.)
    const size_t imax = static_cast<size_t>(std::max_element(t.magnitude.begin(), t.magnitude.end()) -
                                            t.magnitude.begin());
    const size_t end = imax + 1 >= static_cast<size_t>(p.min_contact_samples) ? imax + 1 : t.theta.size();
    const double n = static_cast<double>(end);
    const double tm = std::accumulate(t.theta.begin(), t.theta.begin() + static_cast<std::ptrdiff_t>(end), 0.0) / n;
    const double mm =
        std::accumulate(t.magnitude.begin(), t.magnitude.begin() + static_cast<std::ptrdiff_t>(end), 0.0) / n;
    double sxx = 0.0, sxy = 0.0;
    double tmin = t.theta.front(), tmax = t.theta.front();
    for (size_t i = 0; i < end; ++i) {
      sxx += (t.theta[i] - tm) * (t.theta[i] - tm);
      sxy += (t.theta[i] - tm) * (t.magnitude[i] - mm);
      tmin = std::min(tmin, t.theta[i]);
      tmax = std::max(tmax, t.theta[i]);
    }
    const double k = sxx > 0.0 ? sxy / sxx : 0.0;
    if (tmax - tmin >= p.min_theta_span && k > 0.0) {
      // The contact began at most Δθ = threshold·length/bend_gain before the first sample above
      // the floor (|d| reaches the floor soonest for a contact at the tip), and not after it: a
      // flat, noisy fit must not extrapolate beyond that.
      const double first = t.theta.front();
      const double earliest = first - p.contact_threshold * g.length / g.bend_gain;
      c.theta_contact = std::clamp(tm - mm / k, earliest, first);
      c.radius = std::clamp(g.bend_gain / k, 1e-3 * g.length, g.length);
    } else {
      c.fitted = false;
      c.theta_contact = t.theta.front();
      c.radius = p.fallback_radius_fraction * g.length;
    }
    c.p_contact_in_head = geometry.whisker_point(w, c.theta_contact, c.radius);
    out.push_back(c);
  }
  return out;
}

std::array<float, kSdaSize> compute_sda(const WhiskerTraces& traces) {
  std::array<float, kSdaSize> sda{};
  for (int w = 0; w < kNumWhiskers; ++w) {
    const WhiskerTrace& t = traces[static_cast<size_t>(w)];
    if (t.magnitude.empty()) continue;
    const size_t imax =
        static_cast<size_t>(std::max_element(t.magnitude.begin(), t.magnitude.end()) - t.magnitude.begin());
    const double dt = static_cast<double>(t.utime[imax] - t.utime[0]) * 1e-6;
    if (imax == 0 || dt <= 0.0) continue;
    sda[static_cast<size_t>(w)] = static_cast<float>((t.magnitude[imax] - t.magnitude[0]) / dt);
  }
  return sda;
}

}  // namespace

std::vector<ContactEstimate> estimate_contacts(const WhiskCycleInput& cycle, const RobotGeometry& geometry,
                                               const TactileParams& p) {
  return estimate_contacts(contact_traces(cycle, p), geometry, p);
}

std::array<double, kPfhBins> compute_pfh(const std::vector<Vec3>& pts, const Vec3& viewpoint, int neighbours) {
  std::array<double, kPfhBins> h{};
  const size_t n = pts.size();
  if (n < static_cast<size_t>(kMinPfhPoints)) return h;
  std::vector<Eigen::Vector3d> p(n), nrm(n);
  for (size_t i = 0; i < n; ++i) p[i] = {pts[i].x, pts[i].y, pts[i].z};
  const size_t k = std::clamp<size_t>(static_cast<size_t>(neighbours), 3, n);
  const Eigen::Vector3d vp(viewpoint.x, viewpoint.y, viewpoint.z);
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) {
    std::iota(order.begin(), order.end(), size_t{0});
    // Ties broken by index so the choice does not depend on the pose of the cloud.
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(k), order.end(),
                      [&](size_t a, size_t b) {
                        const double da = (p[a] - p[i]).squaredNorm(), db = (p[b] - p[i]).squaredNorm();
                        return da < db || (da == db && a < b);
                      });
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (size_t j = 0; j < k; ++j) mean += p[order[j]];
    mean /= static_cast<double>(k);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t j = 0; j < k; ++j) {
      const Eigen::Vector3d d = p[order[j]] - mean;
      cov += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    Eigen::Vector3d nv = es.eigenvectors().col(0);  // smallest eigenvalue: the surface normal
    if (nv.dot(vp - p[i]) < 0.0) nv = -nv;
    nrm[i] = nv;
  }
  double pairs = 0.0;
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      Eigen::Vector3d d = p[j] - p[i];
      const double dist = d.norm();
      if (dist < 1e-9) continue;
      d /= dist;
      size_t s = i, t = j;
      // Rusu: the source is the point whose normal is closer to the connecting line.
      if (std::abs(nrm[i].dot(d)) < std::abs(nrm[j].dot(d))) {
        std::swap(s, t);
        d = -d;
      }
      const Eigen::Vector3d& u = nrm[s];
      Eigen::Vector3d v = u.cross(d);
      const double vn = v.norm();
      if (vn < 1e-9) continue;  // normal along the line: the frame is undefined
      v /= vn;
      const Eigen::Vector3d w = u.cross(v);
      const double alpha = v.dot(nrm[t]);
      const double phi = u.dot(d);
      const double theta = std::atan2(w.dot(nrm[t]), u.dot(nrm[t]));
      const int b = (bin_of(alpha, -1.0, 1.0) * kPfhBinsPerDim + bin_of(phi, -1.0, 1.0)) * kPfhBinsPerDim +
                    bin_of(theta, -kPi, kPi);
      h[static_cast<size_t>(b)] += 1.0;
      pairs += 1.0;
    }
  }
  if (pairs > 0.0) {
    for (double& x : h) x /= pairs;
  }
  return h;
}

std::array<double, kPfhBins> compute_point_histogram(const std::vector<Vec3>& pts, const TactileParams& p) {
  std::array<double, kPfhBins> h{};
  if (pts.size() < static_cast<size_t>(kMinPfhPoints)) return h;
  for (const Vec3& q : pts) {
    const int b = (bin_of(q.x, p.histogram_min[0], p.histogram_max[0]) * kPfhBinsPerDim +
                   bin_of(q.y, p.histogram_min[1], p.histogram_max[1])) *
                      kPfhBinsPerDim +
                  bin_of(q.z, p.histogram_min[2], p.histogram_max[2]);
    h[static_cast<size_t>(b)] += 1.0;
  }
  for (double& x : h) x /= static_cast<double>(pts.size());
  return h;
}

std::array<float, kSdaSize> compute_sda(const WhiskCycleInput& cycle, const TactileParams& p) {
  return compute_sda(contact_traces(cycle, p));
}

TactileTemplate make_tactile_template(const WhiskCycleInput& cycle, const RobotGeometry& geometry,
                                      const TactileParams& p) {
  TactileTemplate t;
  const WhiskerTraces traces = contact_traces(cycle, p, &t.sensed);
  const std::vector<ContactEstimate> contacts = estimate_contacts(traces, geometry, p);
  t.num_contacts = static_cast<int>(contacts.size());
  std::vector<Vec3> pts;
  pts.reserve(contacts.size());
  for (const ContactEstimate& c : contacts) pts.push_back(c.p_contact_in_head);
  const std::array<double, kPfhBins> h =
      p.pfh == PfhKind::Rusu ? compute_pfh(pts, Vec3{}, p.normal_neighbours) : compute_point_histogram(pts, p);
  for (int i = 0; i < kPfhBins; ++i) {
    t.pfh[static_cast<size_t>(i)] = static_cast<uint16_t>(std::lround(std::clamp(h[static_cast<size_t>(i)], 0.0, 1.0) * 65535.0));
  }
  t.sda = compute_sda(traces);
  return t;
}

}  // namespace whiskeye::slam
