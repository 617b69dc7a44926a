// Pose-cell attractor network; see pose_cells.h for the model and why it is computed this way.
#include "whiskeye/slam/pose_cells.h"

#include "binary_io.h"

#include "whiskeye/common/se2.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

namespace whiskeye::slam {

namespace {

struct Run {
  int begin, end;
};

// The maximal runs of set entries of a support mask, in index order (a run across the wrap is two).
std::vector<Run> runs(const std::vector<uint8_t>& m) {
  std::vector<Run> out;
  const int n = static_cast<int>(m.size());
  for (int i = 0; i < n;) {
    if (m[static_cast<size_t>(i)] == 0) {
      ++i;
      continue;
    }
    const int b = i;
    while (i < n && m[static_cast<size_t>(i)] != 0) ++i;
    out.push_back({b, i});
  }
  return out;
}

// out += w·in over `count` cells: the convolutions' inner loop. On x86-64 (GCC) built for AVX2 as
// well, chosen at load time; AVX2 without FMA multiplies and adds each cell exactly as SSE2 does, so
// the sums are the same to the bit on every x86-64. Other targets (the aarch64 cross build) and the
// sanitizer builds get the one plain clone, as experience_map.cpp's apply_corrections.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("avx2", "default")))
#endif
void add_span(float* out, const float* in, float w, size_t count) {
  for (size_t k = 0; k < count; ++k) out[k] += w * in[k];
}

}  // namespace

void load(const ParamNode& n, PoseCellParams& p) {
  n.get("dim_xy", p.dim_xy, 5, 256);
  n.get("dim_theta", p.dim_theta, 4, 360);
  n.get("cell_size", p.cell_size, 1e-3, 100.0);
  n.get("exc_radius", p.exc_radius, 0, 10);
  n.get("exc_sigma", p.exc_sigma, 0.05, 20.0);
  n.get("inh_radius", p.inh_radius, 0, 10);
  n.get("inh_sigma", p.inh_sigma, 0.05, 20.0);
  n.get("global_inhibition", p.global_inhibition, 0.0, 0.1);
  n.get("inject_energy", p.inject_energy, 0.0, 10.0);
  n.get("vt_active_decay", p.vt_active_decay, 0.0, 10.0);
  n.get("vt_restore", p.vt_restore, 0.0, 10.0);
  n.get("inject_exclude_newest", p.inject_exclude_newest, 0, 100000);
  n.get("best_radius", p.best_radius, 0, 20);
  n.get("settle_steps", p.settle_steps, 0, 100);
  n.get("max_substeps", p.max_substeps, 1, 10000);
}

PoseCells::PoseCells(const PoseCellParams& params) : params_(params), n_(params.dim_xy), nt_(params.dim_theta) {
  check_radii(params);
  const size_t cells = static_cast<size_t>(n_) * static_cast<size_t>(n_) * static_cast<size_t>(nt_);
  p_.assign(cells, 0.0f);
  a_.assign(cells, 0.0f);
  b_.assign(cells, 0.0f);
  e_.assign(cells, 0.0f);
  i_.assign(cells, 0.0f);
  layer_.assign(static_cast<size_t>(n_) * static_cast<size_t>(n_), 0.0f);
  res_x_.assign(static_cast<size_t>(nt_), 0.0);
  res_y_.assign(static_cast<size_t>(nt_), 0.0);
  build_kernels();
  p_[idx(0, n_ / 2, n_ / 2)] = 1.0f;  // one cell at the grid centre, heading 0
}

void PoseCells::set_params(const PoseCellParams& params) {
  if (params.dim_xy != n_ || params.dim_theta != nt_) {
    throw std::invalid_argument("PoseCells::set_params: dimensions cannot change");
  }
  check_radii(params);
  params_ = params;
  build_kernels();
  best_valid_ = false;
}

void PoseCells::check_radii(const PoseCellParams& p) {
  // The wrap tables (and the dilation and convolutions that read them) reach kPad cells past an edge.
  if (std::max(p.exc_radius, p.inh_radius) > kPad || std::min(p.exc_radius, p.inh_radius) < 0) {
    throw std::invalid_argument("PoseCells: kernel radii must be 0.." + std::to_string(kPad) + ", not " +
                                std::to_string(p.exc_radius) + " and " + std::to_string(p.inh_radius));
  }
}

void PoseCells::build_kernels() {
  auto gauss = [](int r, double sigma) {
    std::vector<float> k(static_cast<size_t>(2 * r + 1));
    double sum = 0.0;
    for (int i = -r; i <= r; ++i) sum += std::exp(-0.5 * i * i / (sigma * sigma));
    for (int i = -r; i <= r; ++i) k[static_cast<size_t>(i + r)] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)) / sum);
    return k;  // 1-D factors normalised to 1, so the 3-D kernel sums to 1
  };
  exc_kernel_ = gauss(params_.exc_radius, params_.exc_sigma);
  inh_kernel_ = gauss(params_.inh_radius, params_.inh_sigma);
  // Room for every row of a layer, padded by the larger radius each side (the x pass).
  row_.assign(static_cast<size_t>(n_) * static_cast<size_t>(n_ + 2 * std::max(params_.exc_radius, params_.inh_radius)), 0.0f);
  sum_.assign(row_.size(), 0.0f);
  wrap_xy_.resize(static_cast<size_t>(n_ + 2 * kPad));
  for (int i = -kPad; i < n_ + kPad; ++i) wrap_xy_[static_cast<size_t>(i + kPad)] = wrap(i, n_);
  wrap_t_.resize(static_cast<size_t>(nt_ + 2 * kPad));
  for (int i = -kPad; i < nt_ + kPad; ++i) wrap_t_[static_cast<size_t>(i + kPad)] = wrap(i, nt_);
  cos_xy_.resize(static_cast<size_t>(n_));
  sin_xy_.resize(static_cast<size_t>(n_));
  cos_t_.resize(static_cast<size_t>(nt_));
  sin_t_.resize(static_cast<size_t>(nt_));
  for (int i = 0; i < n_; ++i) {
    cos_xy_[static_cast<size_t>(i)] = static_cast<float>(std::cos(kTwoPi * i / n_));
    sin_xy_[static_cast<size_t>(i)] = static_cast<float>(std::sin(kTwoPi * i / n_));
  }
  for (int i = 0; i < nt_; ++i) {
    cos_t_[static_cast<size_t>(i)] = static_cast<float>(std::cos(kTwoPi * i / nt_));
    sin_t_[static_cast<size_t>(i)] = static_cast<float>(std::sin(kTwoPi * i / nt_));
  }
}

PoseCells::Support PoseCells::support_of(const std::vector<float>& g, const std::vector<uint8_t>* layers) const {
  Support s;
  s.x.assign(static_cast<size_t>(n_), 0);
  s.y.assign(static_cast<size_t>(n_), 0);
  s.t.assign(static_cast<size_t>(nt_), 0);
  for (int t = 0; t < nt_; ++t) {
    if (layers != nullptr && (*layers)[static_cast<size_t>(t)] == 0) continue;
    for (int y = 0; y < n_; ++y) {
      const float* row = &g[idx(t, y, 0)];
      uint32_t any = 0;
      for (int x = 0; x < n_; ++x) any |= std::bit_cast<uint32_t>(row[x]) << 1;  // ±0 both count as zero
      if (any == 0) continue;
      int lo = 0;
      while (row[lo] == 0.0f) ++lo;
      s.y[static_cast<size_t>(y)] = 1;
      s.t[static_cast<size_t>(t)] = 1;
      for (int x = lo; x < n_; ++x) s.x[static_cast<size_t>(x)] |= static_cast<uint8_t>(row[x] != 0.0f);
    }
  }
  return s;
}

PoseCells::Support PoseCells::dilate(const Support& s, int r) const {
  auto dil = [r](const std::vector<uint8_t>& m, const std::vector<int>& wrap) {
    const int n = static_cast<int>(m.size());
    std::vector<uint8_t> out(m.size(), 0);
    for (int i = 0; i < n; ++i) {
      if (m[static_cast<size_t>(i)] == 0) continue;
      for (int k = -r; k <= r; ++k) out[static_cast<size_t>(wrap[static_cast<size_t>(kPad + i + k)])] = 1;
    }
    return out;
  };
  return {dil(s.x, wrap_xy_), dil(s.y, wrap_xy_), dil(s.t, wrap_t_)};
}

PoseCells::Support PoseCells::convolve(const std::vector<float>& src, std::vector<float>& dst,
                                       const std::vector<float>& kernel, int r, const Support& s,
                                       const Support& region) {
  const Support d = dilate(s, r);
  const int taps = 2 * r + 1;
  const float* k = kernel.data();
  // Every pass adds whole runs of consecutive rows at once: the rows of a run of y are contiguous, so
  // the inner loop is one long span, which vectorises where a row of 21 cells does not. Each output
  // cell receives its taps in order from +0, so the sums are those of plain per-cell loops to the
  // bit (PoseCells.DynamicsEqualThePlainFullGridComputationToTheBit compares the two).
  const std::vector<Run> s_y = runs(s.y), d_y = runs(d.y), region_y = runs(region.y);
  const size_t row = static_cast<size_t>(n_);
  // Pass x: rows (t ∈ s.t, y ∈ s.y). A run of rows is copied into `row_` with r wrapped cells each
  // side (stride n + 2r), so each tap is one span over the whole run: the cells past a row's end
  // are computed and ignored. Cell x of a row gets Σ_j w_j·in[x + j − r], wrapped, taps in order.
  const size_t stride = row + 2 * static_cast<size_t>(r);
  const int* wx = &wrap_xy_[static_cast<size_t>(kPad - r)];
  for (int t = 0; t < nt_; ++t) {
    if (s.t[static_cast<size_t>(t)] == 0) continue;
    for (const Run& q : s_y) {
      const size_t rows = static_cast<size_t>(q.end - q.begin);
      for (size_t i = 0; i < rows; ++i) {
        const float* in = &src[idx(t, q.begin + static_cast<int>(i), 0)];
        float* padded = &row_[i * stride];
        if (r <= n_) {
          std::copy(in + (n_ - r), in + n_, padded);
          std::copy(in, in + n_, padded + r);
          std::copy(in, in + r, padded + r + n_);
        } else {
          for (size_t c = 0; c < stride; ++c) padded[c] = in[wx[c]];
        }
      }
      // The last row's ignored tail is left out, so no tap reads past the run.
      const size_t span = rows * stride - 2 * static_cast<size_t>(r);
      std::fill_n(sum_.begin(), span, 0.0f);
      for (int j = 0; j < taps; ++j) add_span(sum_.data(), &row_[static_cast<size_t>(j)], k[j], span);
      for (size_t i = 0; i < rows; ++i) {
        std::copy_n(&sum_[i * stride], row, &a_[idx(t, q.begin + static_cast<int>(i), 0)]);
      }
    }
  }
  // Pass y: rows (t ∈ s.t, y ∈ d.y) from the rows of pass x that exist (y + j − r ∈ s.y).
  for (int t = 0; t < nt_; ++t) {
    if (s.t[static_cast<size_t>(t)] == 0) continue;
    for (const Run& q : d_y) std::fill_n(&b_[idx(t, q.begin, 0)], static_cast<size_t>(q.end - q.begin) * row, 0.0f);
    for (int j = 0; j < taps; ++j) {
      const float w = k[j];
      for (const Run& q : s_y) {
        // Input rows [q.begin, q.end) land on output rows from wrap(q.begin − (j − r)), maybe wrapping.
        const int first = wrap_xy_[static_cast<size_t>(kPad + q.begin - (j - r))];
        const int len = q.end - q.begin, head = std::min(len, n_ - first);
        add_span(&b_[idx(t, first, 0)], &a_[idx(t, q.begin, 0)], w, static_cast<size_t>(head) * row);
        if (head < len) add_span(&b_[idx(t, 0, 0)], &a_[idx(t, q.begin + head, 0)], w, static_cast<size_t>(len - head) * row);
      }
    }
  }
  // Pass θ: every row of `region` (⊇ d) is written, zero where nothing reaches; rows outside the
  // region are never read by the caller.
  for (int t = 0; t < nt_; ++t) {
    if (region.t[static_cast<size_t>(t)] == 0) continue;
    for (const Run& q : region_y) std::fill_n(&dst[idx(t, q.begin, 0)], static_cast<size_t>(q.end - q.begin) * row, 0.0f);
    if (d.t[static_cast<size_t>(t)] == 0) continue;
    for (int j = 0; j < taps; ++j) {
      const int ti = wrap_t_[static_cast<size_t>(kPad + t + j - r)];
      if (s.t[static_cast<size_t>(ti)] == 0) continue;
      const float w = k[j];
      for (const Run& q : d_y) {
        add_span(&dst[idx(t, q.begin, 0)], &b_[idx(ti, q.begin, 0)], w, static_cast<size_t>(q.end - q.begin) * row);
      }
    }
  }
  return d;
}

void PoseCells::dynamics() {
  // A translation moves activity within its layer: the layers that held it still hold it all.
  if (support_dirty_) support_ = support_of(p_, t_mask_valid_ ? &support_.t : nullptr);
  const Support region = dilate(dilate(support_, params_.exc_radius), params_.inh_radius);
  const Support se = convolve(p_, e_, exc_kernel_, params_.exc_radius, support_, region);
  convolve(e_, i_, inh_kernel_, params_.inh_radius, se, region);
  // The new activity lies inside `region`; outside it p_ is already zero (the old support is inside).
  const float g = static_cast<float>(params_.global_inhibition);
  Support next;
  next.x.assign(static_cast<size_t>(n_), 0);
  next.y.assign(static_cast<size_t>(n_), 0);
  next.t.assign(static_cast<size_t>(nt_), 0);
  double total = 0.0;
  for (int t = 0; t < nt_; ++t) {
    if (region.t[static_cast<size_t>(t)] == 0) continue;
    for (int y = 0; y < n_; ++y) {
      if (region.y[static_cast<size_t>(y)] == 0) continue;
      float* row = &p_[idx(t, y, 0)];
      const float* e = &e_[idx(t, y, 0)];
      const float* in = &i_[idx(t, y, 0)];
      uint32_t any = 0;
      for (int x = 0; x < n_; ++x) {  // no branch, no byte store: it vectorises
        const float v = e[x] - in[x];
        const float q = v >= g ? v - g : 0.0f;
        row[x] = q;
        any |= std::bit_cast<uint32_t>(q) << 1;  // ±0 both count as zero
      }
      if (any == 0) continue;
      int lo = 0, hi = n_ - 1;
      while (row[lo] == 0.0f) ++lo;
      while (row[hi] == 0.0f) --hi;
      next.y[static_cast<size_t>(y)] = 1;
      next.t[static_cast<size_t>(t)] = 1;
      // The row's sum in x order from its first to its last non-zero cell: the zeros outside add
      // nothing (every value is ≥ +0), so this is the whole row's sum to the bit.
      float row_sum = 0.0f;
      for (int x = lo; x <= hi; ++x) {
        row_sum += row[x];
        next.x[static_cast<size_t>(x)] |= static_cast<uint8_t>(row[x] != 0.0f);
      }
      total += row_sum;
    }
  }
  if (!(total > 0.0)) {
    // Everything was inhibited (only possible with extreme parameters): restart at the centre
    // rather than divide by zero.
    std::fill(p_.begin(), p_.end(), 0.0f);
    p_[idx(0, n_ / 2, n_ / 2)] = 1.0f;
    support_dirty_ = true;
    t_mask_valid_ = false;
    return;
  }
  const auto inv = static_cast<float>(1.0 / total);
  for (int t = 0; t < nt_; ++t) {
    if (next.t[static_cast<size_t>(t)] == 0) continue;
    for (int y = 0; y < n_; ++y) {
      if (next.y[static_cast<size_t>(y)] == 0) continue;
      float* row = &p_[idx(t, y, 0)];
      for (int x = 0; x < n_; ++x) row[x] *= inv;
    }
  }
  support_ = std::move(next);
  support_dirty_ = false;
  t_mask_valid_ = true;
}

void PoseCells::translate_layers(double vx_cells, double vy_cells) {
  const size_t sheet = static_cast<size_t>(n_) * static_cast<size_t>(n_);
  bool moved_xy = false;
  for (int t = 0; t < nt_; ++t) {
    // Every layer's remainder follows the motion, occupied or not, so that activity spreading into
    // a layer finds it consistent with its neighbours.
    const double c = cos_t_[static_cast<size_t>(t)], s = sin_t_[static_cast<size_t>(t)];
    double& rx = res_x_[static_cast<size_t>(t)];
    double& ry = res_y_[static_cast<size_t>(t)];
    rx += c * vx_cells - s * vy_cells;
    ry += s * vx_cells + c * vy_cells;
    const double kx = std::round(rx), ky = std::round(ry);
    if (kx == 0.0 && ky == 0.0) continue;
    rx -= kx;
    ry -= ky;
    // Occupied layers: a translation never changes which layers hold activity.
    if (t_mask_valid_ && support_.t[static_cast<size_t>(t)] == 0) continue;
    float* layer = &p_[idx(t, 0, 0)];
    moved_xy = true;
    const int ix = wrap(static_cast<int>(kx), n_), iy = wrap(static_cast<int>(ky), n_);
    std::copy(layer, layer + sheet, layer_.begin());
    for (int y = 0; y < n_; ++y) {
      const float* src = &layer_[static_cast<size_t>(wrap(y - iy, n_) * n_)];
      float* out = layer + static_cast<size_t>(y * n_);
      // Exact cyclic shift of the row by ix: two contiguous copies.
      std::copy(src + (n_ - ix), src + n_, out);
      std::copy(src, src + (n_ - ix), out + ix);
    }
  }
  if (moved_xy) support_dirty_ = true;
}

void PoseCells::rotate(double dtheta_cells) {
  res_t_ += dtheta_cells;
  const double k = std::round(res_t_);
  if (k == 0.0) return;
  res_t_ -= k;
  const int it = wrap(static_cast<int>(k), nt_);
  const size_t sheet = static_cast<size_t>(n_) * static_cast<size_t>(n_);
  a_ = p_;
  for (int t = 0; t < nt_; ++t) {
    std::copy_n(&a_[idx(wrap(t - it, nt_), 0, 0)], sheet, &p_[idx(t, 0, 0)]);
  }
  if (t_mask_valid_) {
    const std::vector<uint8_t> m = support_.t;
    for (int t = 0; t < nt_; ++t) support_.t[static_cast<size_t>(t)] = m[static_cast<size_t>(wrap(t - it, nt_))];
  }
  // The sub-cell remainders travel with the activity they belong to.
  const std::vector<double> rx = res_x_, ry = res_y_;
  for (int t = 0; t < nt_; ++t) {
    res_x_[static_cast<size_t>(t)] = rx[static_cast<size_t>(wrap(t - it, nt_))];
    res_y_[static_cast<size_t>(t)] = ry[static_cast<size_t>(wrap(t - it, nt_))];
  }
}

void PoseCells::step(double vx, double vy, double omega, double dt) {
  best_valid_ = false;
  dynamics();
  if (dt <= 0.0) return;
  const double trans = std::hypot(vx, vy) * dt / params_.cell_size;
  const double rot = omega * dt / (kTwoPi / nt_);
  const int sub = std::clamp(static_cast<int>(std::ceil(std::max(trans, std::abs(rot)))), 1, params_.max_substeps);
  for (int i = 0; i < sub; ++i) {
    translate_layers(vx * dt / sub / params_.cell_size, vy * dt / sub / params_.cell_size);
    rotate(rot / sub);
  }
}

void PoseCells::settle() {
  best_valid_ = false;
  dynamics();
}

void PoseCells::inject(double x, double y, double theta, double energy) {
  if (!(energy > 0.0)) return;
  best_valid_ = false;
  const int ix = wrap(static_cast<int>(std::lround(x)), n_);
  const int iy = wrap(static_cast<int>(std::lround(y)), n_);
  const int it = wrap(static_cast<int>(std::lround(theta)), nt_);
  p_[idx(it, iy, ix)] += static_cast<float>(energy);
  support_dirty_ = true;
  t_mask_valid_ = false;
}

void PoseCells::relocate(double x, double y, double theta) {
  std::fill(p_.begin(), p_.end(), 0.0f);
  std::fill(res_x_.begin(), res_x_.end(), 0.0);
  std::fill(res_y_.begin(), res_y_.end(), 0.0);
  p_[idx(wrap(static_cast<int>(std::lround(theta)), nt_), wrap(static_cast<int>(std::lround(y)), n_),
         wrap(static_cast<int>(std::lround(x)), n_))] = 1.0f;
  best_valid_ = false;
  support_dirty_ = true;
  t_mask_valid_ = false;
  dynamics();
}

void PoseCells::argmax(int& x, int& y, int& t) const {
  // The first largest cell. When the occupied layers are known, only they are scanned: the others
  // are zero, and the activity (normalised to sum 1) has a cell above zero in an occupied layer.
  size_t m = 0;
  if (t_mask_valid_) {
    const size_t sheet = static_cast<size_t>(n_) * static_cast<size_t>(n_);
    float best = -1.0f;
    for (int l = 0; l < nt_; ++l) {
      if (support_.t[static_cast<size_t>(l)] == 0) continue;
      const auto first = p_.begin() + static_cast<std::ptrdiff_t>(idx(l, 0, 0));
      const auto it = std::max_element(first, first + static_cast<std::ptrdiff_t>(sheet));
      if (*it > best) {
        best = *it;
        m = static_cast<size_t>(it - p_.begin());
      }
    }
  } else {
    m = static_cast<size_t>(std::max_element(p_.begin(), p_.end()) - p_.begin());
  }
  x = static_cast<int>(m % static_cast<size_t>(n_));
  y = static_cast<int>((m / static_cast<size_t>(n_)) % static_cast<size_t>(n_));
  t = static_cast<int>(m / (static_cast<size_t>(n_) * static_cast<size_t>(n_)));
}

void PoseCells::best(double& bx, double& by, double& bt) const {
  if (!best_valid_) {
    compute_best(best_x_, best_y_, best_t_);
    best_valid_ = true;
  }
  bx = best_x_;
  by = best_y_;
  bt = best_t_;
}

void PoseCells::compute_best(double& bx, double& by, double& bt) const {
  int x0 = 0, y0 = 0, t0 = 0;
  argmax(x0, y0, t0);
  const int r = params_.best_radius;
  double cx = 0, sx = 0, cy = 0, sy = 0, ct = 0, st = 0, mass = 0, rx = 0, ry = 0;
  for (int dt = -r; dt <= r; ++dt) {
    const int t = wrap(t0 + dt, nt_);
    double layer_mass = 0.0;
    for (int dy = -r; dy <= r; ++dy) {
      const int y = wrap(y0 + dy, n_);
      for (int dx = -r; dx <= r; ++dx) {
        const int x = wrap(x0 + dx, n_);
        const double v = p_[idx(t, y, x)];
        if (v == 0.0) continue;
        cx += v * cos_xy_[static_cast<size_t>(x)];
        sx += v * sin_xy_[static_cast<size_t>(x)];
        cy += v * cos_xy_[static_cast<size_t>(y)];
        sy += v * sin_xy_[static_cast<size_t>(y)];
        ct += v * cos_t_[static_cast<size_t>(t)];
        st += v * sin_t_[static_cast<size_t>(t)];
        layer_mass += v;
      }
    }
    mass += layer_mass;
    rx += layer_mass * res_x_[static_cast<size_t>(t)];
    ry += layer_mass * res_y_[static_cast<size_t>(t)];
  }
  // The grid holds activity at whole cells; the carried sub-cell motion completes the estimate.
  const double ox = mass > 0.0 ? rx / mass : 0.0, oy = mass > 0.0 ? ry / mass : 0.0;
  auto cell = [](double s, double c, double offset, int n) {
    double v = wrap_angle_positive(std::atan2(s, c)) * n / kTwoPi + offset;
    v = std::fmod(v, static_cast<double>(n));
    if (v < 0.0) v += n;
    return v >= n ? v - n : v;
  };
  bx = cell(sx, cx, ox, n_);
  by = cell(sy, cy, oy, n_);
  bt = cell(st, ct, res_t_, nt_);
}

double PoseCells::distance(double x1, double y1, double t1, double x2, double y2, double t2) const {
  auto d = [](double a, double b, int n) {
    const double v = std::fmod(std::abs(a - b), static_cast<double>(n));
    return std::min(v, n - v);
  };
  const double dx = d(x1, x2, n_), dy = d(y1, y2, n_), dt = d(t1, t2, nt_);
  return std::sqrt(dx * dx + dy * dy + dt * dt);
}

double PoseCells::packet_fraction() const {
  int x0 = 0, y0 = 0, t0 = 0;
  argmax(x0, y0, t0);
  const int r = params_.best_radius;
  double in = 0.0, total = 0.0;
  for (float v : p_) total += v;
  for (int dt = -r; dt <= r; ++dt) {
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) in += p_[idx(wrap(t0 + dt, nt_), wrap(y0 + dy, n_), wrap(x0 + dx, n_))];
    }
  }
  return total > 0.0 ? in / total : 0.0;
}

void PoseCells::serialise(std::vector<uint8_t>& out) const {
  bin::put<int32_t>(out, n_);
  bin::put<int32_t>(out, nt_);
  bin::put_vec(out, p_);
  bin::put_vec(out, res_x_);
  bin::put_vec(out, res_y_);
  bin::put<double>(out, res_t_);
}

void PoseCells::deserialise(const std::vector<uint8_t>& in, size_t& pos) {
  const auto n = bin::get<int32_t>(in, pos);
  const auto nt = bin::get<int32_t>(in, pos);
  if (n != n_ || nt != nt_) {
    throw std::runtime_error("checkpoint: pose cells are " + std::to_string(n) + "x" + std::to_string(n) + "x" +
                             std::to_string(nt) + ", the parameters say " + std::to_string(n_) + "x" +
                             std::to_string(n_) + "x" + std::to_string(nt_));
  }
  std::vector<float> p = bin::get_vec<float>(in, pos);
  if (p.size() != p_.size()) throw std::runtime_error("checkpoint: pose-cell array has the wrong length");
  std::vector<double> rx = bin::get_vec<double>(in, pos), ry = bin::get_vec<double>(in, pos);
  if (rx.size() != res_x_.size() || ry.size() != res_y_.size()) {
    throw std::runtime_error("checkpoint: pose-cell remainders have the wrong length");
  }
  const double rt = bin::get<double>(in, pos);
  const auto finite = [](auto v) { return std::isfinite(v); };
  if (!std::all_of(p.begin(), p.end(), finite) || !std::all_of(rx.begin(), rx.end(), finite) ||
      !std::all_of(ry.begin(), ry.end(), finite) || !std::isfinite(rt)) {
    throw std::runtime_error("checkpoint: pose-cell activity or remainders are not finite");
  }
  res_t_ = rt;
  best_valid_ = false;
  p_ = std::move(p);
  support_dirty_ = true;
  t_mask_valid_ = false;
  res_x_ = std::move(rx);
  res_y_ = std::move(ry);
}

}  // namespace whiskeye::slam
