// Tactile template from one whisk cycle (paper Algorithm 1 "tactile process"):
//   1. contact detection per whisker: |deflection| (after removing the calibrated whisking-speed
//      term) above a noise floor for enough samples;
//   2. contact point per whisker in the head frame, estimated from θ and deflection with the whisker
//      geometry (never from simulator ground truth). Model: a point contact at radial distance r
//      bends the whisker so that |deflection| ≈ bend_gain·(θ − θ_c)/r once θ passes the contact
//      angle θ_c. A least-squares line |d| = k·(θ − θ_c) over the rising part of the contact
//      (first contact sample to maximum deflection) gives k and θ_c (θ_c clamped to what the noise
//      floor allows); r = bend_gain/k clamped to (0, length]; p = whisker_point(w, θ_c, r);
//   3. PFH: Rusu's point-pair features (α, φ, θ; 5 bins each → 125) over the contact points, with
//      normals from PCA of each point's k nearest neighbours oriented towards the head origin;
//      invariant to a rigid motion of the cloud (and its viewpoint). Alternative: a plain 3-D
//      histogram of the contact points over fixed bounds (the paper's "N-D histogram");
//   4. SDA: per whisker, slope (per second) of |deflection| from the first contact sample to the
//      sample of maximum deflection in the cycle; 0 without contact.
#pragma once

#include "whiskeye/common/params.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/types.h"

#include <array>
#include <cstdint>
#include <vector>

namespace whiskeye::slam {

constexpr int kPfhBinsPerDim = 5;
constexpr int kPfhBins = kPfhBinsPerDim * kPfhBinsPerDim * kPfhBinsPerDim;  // 125
constexpr int kSdaSize = kNumWhiskers;
constexpr uint32_t kAllWhiskersSensed = (1u << kNumWhiskers) - 1u;
// A PFH needs this many contact points (normals from neighbours, pairs of points); fewer: all zero.
constexpr int kMinPfhPoints = 3;

enum class PfhKind { Rusu, Histogram };

struct TactileParams {
  double contact_threshold = 0.04;    // |deflection| noise floor (sensor units)
  int min_contact_samples = 3;        // fewer samples above the floor: no contact (debounce)
  bool use_contact_flags = false;     // also require the head's own contact flag
  // Whisking-speed term of the x deflection, per rad/s (a moving whisker bends against its motion;
  // the simulator's plant uses 0.004). Removed before detection and fitting; 0 = none.
  double speed_gain = 0.004;
  double min_theta_span = 0.01;       // rad; a smaller θ range cannot give a slope: fallback radius
  double fallback_radius_fraction = 0.8;  // r = fraction·length when the slope fit is degenerate
  PfhKind pfh = PfhKind::Rusu;
  int normal_neighbours = 5;          // k nearest neighbours (including the point) for the normal
  // Bounds of the plain-histogram PFH, head frame, m (fixed edges: comparable across cycles).
  std::array<double, 3> histogram_min{-0.05, -0.25, -0.10};
  std::array<double, 3> histogram_max{0.30, 0.25, 0.10};
};
void load(const ParamNode& node, TactileParams& p);

struct ContactEstimate {
  int whisker = -1;
  double theta_contact = 0.0;  // rad
  double radius = 0.0;         // m along the whisker
  Vec3 p_contact_in_head;
  bool fitted = true;          // false: the fallback radius was used
};

struct TactileTemplate {
  std::array<uint16_t, kPfhBins> pfh{};  // fraction of point pairs per bin, quantised ·65535
  std::array<float, kSdaSize> sda{};     // deflection per second
  int num_contacts = 0;                  // whiskers in contact this cycle
  // Bit w: whisker w had a valid, finite sample this cycle. Matching compares the SDA over the
  // whiskers both the query and the stored template sensed (a dead whisker, or one whose board is
  // offline, then or now, is neither agreement nor disagreement); stored with the template.
  uint32_t sensed = kAllWhiskersSensed;
  bool has_contact() const { return num_contacts > 0; }
  // Enough contacts for a PFH: touch felt a shape, not only a whisker or two.
  bool has_shape() const { return num_contacts >= kMinPfhPoints; }
};

// Contact points of one whisk cycle. Invalid samples are skipped.
std::vector<ContactEstimate> estimate_contacts(const WhiskCycleInput& cycle, const RobotGeometry& geometry,
                                               const TactileParams& params);

// Fractions (sum 1, or all zero for < 3 points) per bin. `viewpoint` orients the normals.
std::array<double, kPfhBins> compute_pfh(const std::vector<Vec3>& points, const Vec3& viewpoint, int neighbours);
std::array<double, kPfhBins> compute_point_histogram(const std::vector<Vec3>& points, const TactileParams& params);
std::array<float, kSdaSize> compute_sda(const WhiskCycleInput& cycle, const TactileParams& params);

TactileTemplate make_tactile_template(const WhiskCycleInput& cycle, const RobotGeometry& geometry,
                                      const TactileParams& params);

}  // namespace whiskeye::slam
