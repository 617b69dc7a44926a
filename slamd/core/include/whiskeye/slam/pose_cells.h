// Pose cells: a 3-D continuous attractor network over (x, y, θ) with wrap-around on every axis
// (RatSLAM). One step: Gaussian excitation → subtract the Gaussian inhibition of the result →
// global inhibition (cells below g become 0, others lose g) → normalise to sum 1 → path
// integration. Both convolutions are separable and restricted to the region the activity can
// reach (the packet's support dilated by the kernel radius), so a step costs a few tens of µs
// instead of one 7³ kernel per active cell.
//
// Path integration uses body-frame vx, vy and ω (the WhiskEye moves sideways): θ layer k (heading
// φ_k = 2πk/N_θ) moves by R(φ_k)·(vx, vy)·dt/cell_size. Activity is only ever moved by whole cells
// (an exact cyclic shift: no interpolation blur, and no pinning — with OpenRatSLAM's bilinear
// sub-cell shift the attractor pulls the packet back to cell centres and it under-reports motion
// by ≈13 % at 0.1 cell per step); each layer carries its sub-cell remainder, which moves with its
// activity on rotation and is added to the best estimate. Each shift is exact at any speed (the
// network's excitation and inhibition still drag a moving packet a little, docs/slam-core.md); a
// step that moves more than one cell is split into sub-steps so that an arc (v and ω together) is
// followed.
// Rotation along θ likewise.
#pragma once

#include "whiskeye/common/params.h"

#include <cstdint>
#include <vector>

namespace whiskeye::slam {

struct PoseCellParams {
  int dim_xy = 21;
  int dim_theta = 36;
  double cell_size = 0.1;          // m per cell in x and y
  int exc_radius = 3;              // excitation kernel (2r+1)³ (OpenRatSLAM: 7³, σ = 1)
  double exc_sigma = 1.0;          // cells
  int inh_radius = 2;              // inhibition kernel 5³, σ = 2
  double inh_sigma = 2.0;
  double global_inhibition = 1e-4;
  double inject_energy = 0.1;      // energy a matched template injects (original ViTa: 0.1)
  double vt_active_decay = 0.5;    // decay added per match of a template
  double vt_restore = 0.04;        // decay relaxed per cycle
  int inject_exclude_newest = 10;  // the newest templates do not inject (they are where we are)
  int best_radius = 3;             // box for the circular-mean best estimate
  int settle_steps = 1;            // zero-motion steps after an injection, before the action rule
  int max_substeps = 64;           // cap on path-integration sub-steps per odometry sample
};
void load(const ParamNode& node, PoseCellParams& p);

class PoseCells {
 public:
  explicit PoseCells(const PoseCellParams& params);

  // One network step with the body-frame motion (m/s, rad/s) held over dt seconds.
  void step(double vx, double vy, double omega, double dt);
  // Dynamics only (excite, inhibit, normalise), no motion.
  void settle();
  // Adds energy at the cell nearest to (x, y, θ) in cells.
  void inject(double x, double y, double theta, double energy);
  // Moves the whole activity to one packet at the cell nearest to (x, y, θ) (a re-localisation the
  // experience map accepted beyond the packet's reach: the packet follows the map instead of
  // spawning experiences where it drifted to). Sub-cell remainders restart at 0; the network then
  // settles once, so best() is the packet's centre.
  void relocate(double x, double y, double theta);
  // Best estimate in cells: argmax, then circular means of the marginals in a box around it.
  // Cached until the network next changes (slamd asks for it at every odometry sample).
  void best(double& x, double& y, double& theta) const;
  // Wrapped Euclidean distance in cells between two (x, y, θ).
  double distance(double x1, double y1, double t1, double x2, double y2, double t2) const;

  // Fraction of the total activity within the best-estimate box (1 = a single compact packet).
  double packet_fraction() const;
  const std::vector<float>& activity() const { return p_; }  // [θ][y][x]
  const PoseCellParams& params() const { return params_; }
  // Same dimensions; kernels rebuilt. Throws std::invalid_argument (and changes nothing) for other
  // dimensions or kernel radii beyond 16 (load() caps them at 10).
  void set_params(const PoseCellParams& params);

  void serialise(std::vector<uint8_t>& out) const;
  void deserialise(const std::vector<uint8_t>& in, size_t& pos);  // dimensions must match

 private:
  struct Support {
    std::vector<uint8_t> x, y, t;  // 1 where some cell with that index may be non-zero
  };
  void dynamics();
  void argmax(int& x, int& y, int& t) const;
  // `layers`: when given, the θ layers that may hold activity (the others are known to be zero).
  Support support_of(const std::vector<float>& g, const std::vector<uint8_t>* layers = nullptr) const;
  Support dilate(const Support& s, int r) const;
  // dst = separable kernel * src over the rows of `region` (⊇ the result's support); src is zero
  // outside `s`; returns the result's support.
  Support convolve(const std::vector<float>& src, std::vector<float>& dst, const std::vector<float>& kernel, int r,
                   const Support& s, const Support& region);
  void translate_layers(double vx_cells, double vy_cells);
  void rotate(double dtheta_cells);
  static void check_radii(const PoseCellParams& p);  // throws std::invalid_argument beyond 0..kPad
  void build_kernels();
  void compute_best(double& x, double& y, double& theta) const;
  size_t idx(int t, int y, int x) const {
    return (static_cast<size_t>(t) * static_cast<size_t>(n_) + static_cast<size_t>(y)) * static_cast<size_t>(n_) +
           static_cast<size_t>(x);
  }
  int wrap(int i, int n) const { return ((i % n) + n) % n; }

  PoseCellParams params_;
  int n_ = 0;   // x, y size
  int nt_ = 0;  // θ size
  std::vector<float> p_, a_, b_, e_, i_;
  std::vector<float> exc_kernel_, inh_kernel_;  // 1-D, normalised
  std::vector<float> layer_;                     // one x-y sheet of scratch
  std::vector<float> row_, sum_;                 // scratch of the x pass: padded rows and their sums
  std::vector<float> cos_xy_, sin_xy_, cos_t_, sin_t_;  // circular-mean tables
  static constexpr int kPad = 16;  // ≥ any kernel radius (load() caps radii at 10)
  std::vector<int> wrap_xy_, wrap_t_;  // i + kPad → i mod n, for i in [−kPad, n + kPad)
  // Sub-cell motion not yet applied to the grid: per θ layer in x/y (world cells), and in θ.
  std::vector<double> res_x_, res_y_;
  double res_t_ = 0.0;
  Support support_;            // rows/columns that may hold activity
  bool support_dirty_ = true;  // recompute before use
  bool t_mask_valid_ = false;  // support_.t is exact (translations keep it; rotations shift it)
  // best() of the current state; every public mutator clears best_valid_.
  mutable bool best_valid_ = false;
  mutable double best_x_ = 0.0, best_y_ = 0.0, best_t_ = 0.0;
};

}  // namespace whiskeye::slam
