// Template memory and matching. The visual term is the hot loop (every stored template, every
// shift, every cycle): templates are stored column-major, so each shift's overlap is one contiguous
// run, and all shifts' sums of absolute byte differences are taken in one pass (sad.h: AVX-512BW /
// AVX2 chosen at run time, the same integers as the plain loop).
#include "whiskeye/slam/template_store.h"

#include "binary_io.h"
#include "sad.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <optional>

namespace whiskeye::slam {

void load(const ParamNode& n, MatchParams& p) {
  n.get("shift_max", p.shift_max, 0, 512);
  n.get("shift_step", p.shift_step, 1, 512);
  n.get("sigma_visual", p.sigma_visual, 1e-9, 1e9);
  n.get("sigma_pfh", p.sigma_pfh, 1e-9, 1e9);
  n.get("sigma_sda", p.sigma_sda, 1e-9, 1e9);
  n.get("threshold_visual", p.threshold_visual, 0.0, 1e9);
  n.get("threshold_tactile", p.threshold_tactile, 0.0, 1e9);
  n.get("threshold_vita", p.threshold_vita, 0.0, 1e9);
  n.get("tactile_veto", p.tactile_veto, 0.0, 1e9);
  n.get("threshold_visual_touched", p.threshold_visual_touched, 0.0, 1e9);
  n.get("prefilter_mean_diff", p.prefilter_mean_diff, 0.0, 1.0);
}

namespace {

// Σ|a[i] − b[i]| (sad.h): the plain C++ loop or its SSE2 / AVX2 / AVX-512BW versions, the fastest
// the CPU has picked at run time; all give the same integer.
uint32_t sad_u8(const uint8_t* a, const uint8_t* b, size_t n) { return sad::sad_u8(a, b, n); }

// Row-major → column-major. Stored column-major, a column shift s is a flat offset of s·h and the
// overlap of two templates is ONE contiguous run of (w − |s|)·h bytes: no per-row tails, no
// straddling corrections, just one long vectorised SAD per shift.
void to_column_major(const uint8_t* rm, int w, int h, uint8_t* cm) {
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) cm[static_cast<size_t>(x) * static_cast<size_t>(h) + static_cast<size_t>(y)] = rm[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)];
}

// The matcher's lower bound works on a coarse copy of each template: every column's rows in
// blocks of kBlockRows, each block's floored mean as one byte (a last partial block is left out).
// For one block of k pixels with floored means ā, b̄:  Σ|a − b| ≥ |Σa − Σb| ≥ k·|ā − b̄| − (k − 1).
// Summed over a shift's overlap this bounds its SAD from below, and is a SAD of 1/k as many bytes.
constexpr int kBlockRows = 4;

int blocks_per_column(int h) { return h / kBlockRows; }

void block_means(const uint8_t* cm, int w, int h, uint8_t* out) {
  const int hb = blocks_per_column(h);
  for (int x = 0; x < w; ++x) {
    const uint8_t* c = cm + static_cast<size_t>(x) * static_cast<size_t>(h);
    for (int b = 0; b < hb; ++b) {
      uint32_t s = 0;
      for (int y = 0; y < kBlockRows; ++y) s += c[b * kBlockRows + y];
      out[static_cast<size_t>(x) * static_cast<size_t>(hb) + static_cast<size_t>(b)] = static_cast<uint8_t>(s / kBlockRows);
    }
  }
}

// The bound pays only where it prunes; where it cannot (e.g. uniformly random pixels with visual
// terms only) it would add ~45 % to the scan for nothing. So it is used in blocks of kBlock
// templates and, after a block in which it pruned fewer than half, left out for the next kRest
// blocks (worst case ~6 % added, vita-bench BM_TemplateMatchVisualOnly). Which templates are
// bounded changes only the speed, never the result.
class BoundProbe {
 public:
  bool use() const { return rest_ == 0; }
  void record(bool pruned) {
    pruned_ += pruned ? 1 : 0;
    if (++seen_ < kBlock) return;
    rest_ = 2 * pruned_ < seen_ ? kRest * kBlock : 0;
    seen_ = pruned_ = 0;
  }
  // Called for each template compared without the bound while it rests.
  void skip() {
    if (rest_ > 0) --rest_;
  }

 private:
  static constexpr int kBlock = 64;
  static constexpr int kRest = 7;
  int seen_ = 0, pruned_ = 0, rest_ = 0;
};

// Calls f(s) for the shifts s = 0, +step, −step, +2·step, ... within ±min(shift_max, w − 1): the
// order in which ties go to the smallest |shift|.
template <typename F>
void for_each_shift(int w, int shift_max, int shift_step, F f) {
  const int smax = std::min(shift_max, w - 1);
  for (int k = 0; k * shift_step <= smax; ++k) {
    for (int sign = 1; sign >= -1; sign -= 2) {
      if (k == 0 && sign < 0) continue;
      f(sign * k * shift_step);
    }
  }
}

// Current column c against stored column c − s, both column-major with `per_column` values a column:
// the overlap is one run of `len` values, starting `off` into the current template for s ≥ 0 and
// into the stored one for s < 0.
struct Overlap {
  size_t off, len;
};
Overlap overlap(int w, int per_column, int s) {
  return {static_cast<size_t>(std::abs(s)) * static_cast<size_t>(per_column),
          static_cast<size_t>(w - std::abs(s)) * static_cast<size_t>(per_column)};
}
uint32_t overlap_sad(const uint8_t* cur, const uint8_t* st, int s, Overlap o) {
  return s >= 0 ? sad_u8(cur + o.off, st, o.len) : sad_u8(cur, st + o.off, o.len);
}

// The block-mean bound of shift s's SAD from the SAD of its coarse overlap; hb blocks per column.
uint32_t block_bound(uint32_t coarse_sad, int w, int hb, int s) {
  const uint64_t raw = kBlockRows * static_cast<uint64_t>(coarse_sad);
  const uint64_t slack = overlap(w, hb, s).len * (kBlockRows - 1);
  return raw > slack ? static_cast<uint32_t>(raw - slack) : 0;
}
uint32_t shift_bound(const uint8_t* cur_blocks, const uint8_t* st_blocks, int w, int hb, int s) {
  return block_bound(overlap_sad(cur_blocks, st_blocks, s, overlap(w, hb, s)), w, hb, s);
}

// The shifts in for_each_shift() order; sad::ShiftedImage compares a stored template with the
// current one at all of them in one pass (kBatch at most, the size of the buffers below).
constexpr size_t kBatch = 32;
std::vector<int> shift_list(int w, int shift_max, int shift_step) {
  std::vector<int> shifts;
  for_each_shift(w, shift_max, shift_step, [&](int s) { shifts.push_back(s); });
  return shifts;
}

// visual_distance(), optionally skipping a shift whose bound (`bounds`, from shift_bounds(), in
// for_each_shift() order; nullptr: none) shows it cannot beat the best shift so far: the same
// result either way.
// `shifted`: the current image prepared for these shifts (nullptr: one SAD per shift).
double visual_distance_impl(const uint8_t* cur, const uint8_t* st, const uint32_t* bounds, int w, int h,
                            int shift_max, int shift_step, const sad::ShiftedImage* shifted, int* best_shift) {
  constexpr uint64_t kNone = std::numeric_limits<uint64_t>::max();
  uint64_t best_num = kNone;
  uint64_t best_den = 1;
  int best_s = 0;
  size_t j = 0;
  // Without bounds every shift is compared: all in one pass. With them, shift by shift, so that a
  // hopeless shift costs nothing.
  uint32_t sads[kBatch];
  const bool batch = bounds == nullptr && shifted != nullptr;
  if (batch) shifted->sads(st, sads);
  for_each_shift(w, shift_max, shift_step, [&](int s) {
    const Overlap o = overlap(w, h, s);
    const uint64_t den = o.len;
    // SAD ≥ bound, so bound·best_den ≥ best_num·den rules out the strict improvement below.
    const bool hopeless = bounds != nullptr && best_num != kNone && bounds[j] * best_den >= best_num * den;
    const size_t at = j++;
    if (hopeless) return;
    const uint32_t sad = batch ? sads[at] : overlap_sad(cur, st, s, o);
    // Compare sad/den exactly (cross-multiplied) so the choice never depends on rounding.
    if (best_num == kNone || static_cast<uint64_t>(sad) * best_den < best_num * den) {
      best_num = sad;
      best_den = den;
      best_s = s;
    }
  });
  if (best_shift != nullptr) *best_shift = best_s;
  return static_cast<double>(best_num) / static_cast<double>(best_den) / 255.0;
}

// The block-mean bound of every shift, in for_each_shift() order, into `bounds`; returns a lower
// bound of visual_distance() computed the same way from them: the exact minimum over shifts of
// bound/den ≤ the minimum of SAD/den, and the conversions and the division by 255 are monotone, so
// the double returned is ≤ visual_distance()'s.
double shift_bounds(const uint8_t* cur_blocks, const uint8_t* st_blocks, int w, int h, int shift_max, int shift_step,
                    const sad::ShiftedImage* shifted_blocks, std::vector<uint32_t>& bounds) {
  uint64_t best_num = std::numeric_limits<uint64_t>::max();
  uint64_t best_den = 1;
  bounds.clear();
  uint32_t sads[kBatch];
  const int hb = blocks_per_column(h);
  const bool batch = shifted_blocks != nullptr;
  if (batch) shifted_blocks->sads(st_blocks, sads);
  for_each_shift(w, shift_max, shift_step, [&](int s) {
    const uint32_t b = batch ? block_bound(sads[bounds.size()], w, hb, s) : shift_bound(cur_blocks, st_blocks, w, hb, s);
    const uint64_t den = overlap(w, h, s).len;
    if (bounds.empty() || static_cast<uint64_t>(b) * best_den < best_num * den) {
      best_num = b;
      best_den = den;
    }
    bounds.push_back(b);
  });
  return static_cast<double>(best_num) / static_cast<double>(best_den) / 255.0;
}

uint32_t l1_u16(const uint16_t* __restrict a, const uint16_t* __restrict b, size_t n) {
  uint32_t s = 0;
  for (size_t i = 0; i < n; ++i) s += static_cast<uint32_t>(std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i])));
  return s;
}

float l1_f32(const float* __restrict a, const float* __restrict b, size_t n) {
  float s = 0.0f;
  for (size_t i = 0; i < n; ++i) s += std::abs(a[i] - b[i]);
  return s;
}

// The rules a stored template can match by (match()).
enum class Rule { kSum, kVision, kEvidence };

// The SDA distance over the whiskers both templates sensed, scaled to the whole array: a whisker
// without data in either (dead, its board offline then or now) counts neither as agreement nor as
// disagreement.
double sda_distance(const float* a, uint32_t a_sensed, const float* b, uint32_t b_sensed) {
  const uint32_t both = a_sensed & b_sensed;
  if (both == kAllWhiskersSensed) return l1_f32(a, b, kSdaSize);
  float s = 0.0f;
  int n = 0;
  for (size_t w = 0; w < static_cast<size_t>(kSdaSize); ++w) {
    if ((both >> w & 1u) == 0) continue;
    s += std::abs(a[w] - b[w]);
    ++n;
  }
  return n == 0 ? 0.0 : static_cast<double>(s) * kSdaSize / n;
}

// The error of one stored template under a rule of the fusion (MatchParams::tactile_veto), +∞ where
// the rule does not apply; the vision rule's V/σ_V is scaled onto threshold_vita's scale. Each is
// non-decreasing in `visual`, so a lower bound of the visual term gives a lower bound of the error.
double rule_error(Rule rule, double visual, double pfh, double sda, bool both_shapes, const MatchParams& p) {
  constexpr double kNever = std::numeric_limits<double>::infinity();
  const double tactile = pfh + sda;
  switch (rule) {
    case Rule::kSum:
      return visual + pfh + sda;
    case Rule::kVision:
      if (tactile > p.tactile_veto || p.threshold_visual <= 0.0) return kNever;
      return visual * (p.threshold_vita / p.threshold_visual);
    case Rule::kEvidence:
      if (!both_shapes || visual > p.threshold_visual_touched) return kNever;
      return visual + tactile;
  }
  return kNever;
}

// The rules a query is decided by: the paper's sum, except with Terms::fused (ViTa with both
// senses), where tactile_veto 0 is the sum or, for a cycle that touched nothing, vision's rule, and
// otherwise vision's choice then the evidence of both senses (match() combines the two).
struct Rules {
  std::array<Rule, 2> rules{};
  size_t count = 0;
};
Rules rules_for(const Query& q, const Terms& terms, const MatchParams& p) {
  if (!(terms.fused && terms.visual && terms.tactile)) return {{Rule::kSum}, 1};
  if (p.tactile_veto <= 0.0) return {{q.tactile->has_contact() ? Rule::kSum : Rule::kVision}, 1};
  return {{Rule::kVision, Rule::kEvidence}, 2};
}

}  // namespace

TemplateStore::TemplateStore(int visual_width, int visual_height)
    : width_(visual_width),
      height_(visual_height),
      visual_(pixels()),
      blocks_(blocks()),
      pfh_(kPfhBins),
      sda_(kSdaSize) {}

size_t TemplateStore::blocks() const {
  return static_cast<size_t>(width_) * static_cast<size_t>(blocks_per_column(height_));
}

int TemplateStore::add(const Query& q, double pc_x, double pc_y, double pc_theta) {
  const int id = size();
  const size_t np = pixels();
  if (q.visual != nullptr) {
    if (q.visual->width != width_ || q.visual->height != height_ || q.visual->pixels.size() != np) {
      throw std::invalid_argument("TemplateStore::add: visual template is " + std::to_string(q.visual->width) + "x" +
                                  std::to_string(q.visual->height) + ", the store holds " + std::to_string(width_) +
                                  "x" + std::to_string(height_));
    }
  }
  uint8_t* pixels_cm = visual_.append();  // zeros without a visual part
  if (q.visual != nullptr) to_column_major(q.visual->pixels.data(), width_, height_, pixels_cm);
  visual_mean_.push_back(q.visual != nullptr ? q.visual->mean : 0.0f);
  block_means(pixels_cm, width_, height_, blocks_.append());  // no blocks (nullptr) below 4 rows
  has_visual_.push_back(q.visual != nullptr ? 1 : 0);
  uint16_t* pfh = pfh_.append();
  float* sda = sda_.append();
  if (q.tactile != nullptr) {
    std::copy(q.tactile->pfh.begin(), q.tactile->pfh.end(), pfh);
    std::copy(q.tactile->sda.begin(), q.tactile->sda.end(), sda);
    num_contacts_.push_back(q.tactile->num_contacts);
    sensed_.push_back(q.tactile->sensed);
  } else {
    num_contacts_.push_back(0);
    sensed_.push_back(kAllWhiskersSensed);
  }
  has_tactile_.push_back(q.tactile != nullptr ? 1 : 0);
  pc_.push_back(pc_x);
  pc_.push_back(pc_y);
  pc_.push_back(pc_theta);
  decay_.push_back(0.0);
  return id;
}

double TemplateStore::visual_distance(const uint8_t* cur, const uint8_t* st, int w, int h, int shift_max,
                                      int shift_step, int* best_shift) {
  const std::vector<int> shifts = shift_list(w, shift_max, shift_step);
  if (shifts.size() > kBatch) return visual_distance_impl(cur, st, nullptr, w, h, shift_max, shift_step, nullptr, best_shift);
  const sad::ShiftedImage shifted(cur, w, h, shifts.data(), static_cast<int>(shifts.size()));
  return visual_distance_impl(cur, st, nullptr, w, h, shift_max, shift_step, &shifted, best_shift);
}

TemplateStore::TermScale TemplateStore::scale_of(const MatchParams& p) {
  return {1.0 / p.sigma_visual, 1.0 / (65535.0 * p.sigma_pfh), 1.0 / p.sigma_sda};
}

void TemplateStore::check_query(const Query& q, const Terms& terms, const char* who) const {
  if (terms.visual && q.visual != nullptr &&
      (q.visual->width != width_ || q.visual->height != height_ || q.visual->pixels.size() != pixels())) {
    throw std::invalid_argument(std::string(who) + ": visual template is " + std::to_string(q.visual->width) + "x" +
                                std::to_string(q.visual->height) + ", the store holds " + std::to_string(width_) + "x" +
                                std::to_string(height_));
  }
}

bool TemplateStore::comparable(size_t i, const Query& q, const Terms& terms, const MatchParams& p) const {
  if (terms.visual && (has_visual_[i] == 0 || std::abs(static_cast<double>(visual_mean_[i]) - q.visual->mean) > p.prefilter_mean_diff)) {
    return false;
  }
  return !terms.tactile || has_tactile_[i] != 0;
}

TemplateStore::TactileTerms TemplateStore::tactile_terms(size_t i, const Query& q, const TermScale& scale) const {
  // Touch adds evidence only where both cycles felt a shape (a PFH): one or two whiskers' slopes say
  // too little to let a weak view count.
  return {l1_u16(q.tactile->pfh.data(), pfh_.row(i), kPfhBins) * scale.pfh,
          sda_distance(q.tactile->sda.data(), q.tactile->sensed, sda_.row(i), sensed_[i]) * scale.sda,
          q.tactile->has_shape() && num_contacts_[i] >= kMinPfhPoints};
}

BestMatch TemplateStore::match(const Query& q, const Terms& terms, const MatchParams& p) const {
  BestMatch best;
  if ((!terms.visual && !terms.tactile) || (terms.visual && q.visual == nullptr) ||
      (terms.tactile && q.tactile == nullptr)) {
    return best;
  }
  check_query(q, terms, "TemplateStore::match");
  const size_t np = pixels();
  std::vector<uint8_t> cur;
  if (terms.visual) {
    cur.resize(np);
    to_column_major(q.visual->pixels.data(), width_, height_, cur.data());
  }
  const bool bound = terms.visual && p.lower_bound_prefilter;
  std::vector<uint8_t> cur_blocks;
  std::vector<uint32_t> bounds;  // per shift, of the template being compared
  if (bound) {
    cur_blocks.resize(blocks());
    block_means(cur.data(), width_, height_, cur_blocks.data());
  }
  // The current template (and its block means) prepared for the shifts, once for every comparison.
  const std::vector<int> shifts = shift_list(width_, p.shift_max, p.shift_step);
  const int n_shifts = static_cast<int>(shifts.size());
  std::optional<sad::ShiftedImage> cur_shifted, blocks_shifted;
  if (terms.visual && shifts.size() <= kBatch) {
    cur_shifted.emplace(cur.data(), width_, height_, shifts.data(), n_shifts);
    if (bound) blocks_shifted.emplace(cur_blocks.data(), width_, blocks_per_column(height_), shifts.data(), n_shifts);
  }
  const TermScale scale = scale_of(p);
  // One pass over the store for one or two rules: each rule's argmin (the first on ties), exactly
  // what a pass of its own would find, the visual term computed once for a template any rule still
  // needs. Each rule's error is non-decreasing in the visual term, so the visual term's lower bound
  // bounds it (the same floating-point operations: the library is built with -ffp-contract=off).
  struct Scan {
    std::array<Rule, 2> rules{};
    std::array<BestMatch, 2> best{};
    size_t count = 0;
  };
  const auto scan = [&](const Rules& rules) {
    Scan out;
    out.rules = rules.rules;
    out.count = rules.count;
    BoundProbe probe;
    const int n = size();
    for (int i = 0; i < n; ++i) {
      const auto iu = static_cast<size_t>(i);
      if (!comparable(iu, q, terms, p)) continue;
      double ev = 0.0;
      int shift = 0;
      const TactileTerms t = terms.tactile ? tactile_terms(iu, q, scale) : TactileTerms{};
      const double ep = t.pfh, es = t.sda;
      const auto error = [&](size_t j, double visual) {
        return rule_error(out.rules[j], visual, ep, es, t.both_shapes, p);
      };
      // A rule still needs this template unless it cannot apply, or cannot beat its best so far
      // whatever the visual term (≥ 0): the tactile terms alone may rule it out.
      std::array<bool, 2> live{};
      bool any = false;
      for (size_t j = 0; j < out.count; ++j) {
        const double e0 = error(j, 0.0);
        live[j] = std::isfinite(e0) && !(bound && out.best[j].id >= 0 && e0 >= out.best[j].error);
        any = any || live[j];
      }
      if (!any) continue;
      if (terms.visual) {
        const bool use_bound = bound && probe.use();
        if (bound && !use_bound) probe.skip();
        if (use_bound) {
          const double lower = shift_bounds(cur_blocks.data(), blocks_.row(iu), width_, height_, p.shift_max,
                                            p.shift_step, blocks_shifted ? &*blocks_shifted : nullptr, bounds) *
                               scale.visual;
          // With the bound: no rule can apply (the evidence rule's view limit) or beat its best.
          bool needed = false;
          for (size_t j = 0; j < out.count; ++j) {
            if (!live[j]) continue;
            const double lower_error = error(j, lower);
            live[j] = std::isfinite(lower_error) && !(out.best[j].id >= 0 && lower_error >= out.best[j].error);
            needed = needed || live[j];
          }
          probe.record(!needed);
          if (!needed) continue;
        }
        // A fresh minimum per stored template (the original code carried it across templates).
        ev = visual_distance_impl(cur.data(), visual_.row(iu), use_bound ? bounds.data() : nullptr, width_, height_,
                                  p.shift_max, p.shift_step, cur_shifted ? &*cur_shifted : nullptr, &shift) *
             scale.visual;
      }
      for (size_t j = 0; j < out.count; ++j) {
        if (!live[j]) continue;
        const double e = error(j, ev);
        if (std::isfinite(e) && (out.best[j].id < 0 || e < out.best[j].error)) out.best[j] = {i, e, ev, ep, es, shift};
      }
    }
    return out;
  };
  // One rule: its argmin (tactile_veto 0: the paper's sum, but for a cycle that touched nothing,
  // which vision decides among the templates that touched nothing either).
  const Rules rules = rules_for(q, terms, p);
  if (rules.count == 1) return scan(rules).best[0];
  // The fusion: vision's choice among the templates touch does not object to; only where vision
  // recognises nothing, the evidence of both senses.
  const Scan both_rules = scan(rules);
  const BestMatch& seen = both_rules.best[0];
  const BestMatch& felt = both_rules.best[1];
  if (seen.id >= 0 && seen.error <= p.threshold_vita) return seen;
  return felt.id >= 0 && (seen.id < 0 || felt.error < seen.error) ? felt : seen;
}

TemplateStore::Recogniser::Recogniser(const TemplateStore& store, const Query& q, const Terms& terms,
                                     const MatchParams& p, double tau)
    : store_(store), q_(q), terms_(terms), p_(p), tau_(tau) {
  store.check_query(q, terms, "TemplateStore::Recogniser");
  if (terms_.visual && q_.visual != nullptr) {
    cur_.resize(store.pixels());
    to_column_major(q_.visual->pixels.data(), store.width_, store.height_, cur_.data());
  }
}

Recognition TemplateStore::Recogniser::operator()(int id) const {
  if (id < 0 || id >= store_.size() || (!terms_.visual && !terms_.tactile)) return Recognition::None;
  const auto iu = static_cast<size_t>(id);
  if ((terms_.visual && q_.visual == nullptr) || (terms_.tactile && q_.tactile == nullptr)) return Recognition::None;
  if (!store_.comparable(iu, q_, terms_, p_)) return Recognition::None;
  const TermScale scale = scale_of(p_);
  double ev = 0.0;
  if (terms_.visual) {
    ev = visual_distance(cur_.data(), store_.visual_.row(iu), store_.width_, store_.height_, p_.shift_max, p_.shift_step,
                         nullptr) *
         scale.visual;
  }
  const TactileTerms t = terms_.tactile ? store_.tactile_terms(iu, q_, scale) : TactileTerms{};
  // Recognised if any of match()'s rules for this query takes it within τ.
  const Rules rules = rules_for(q_, terms_, p_);
  for (size_t j = 0; j < rules.count; ++j) {
    if (rule_error(rules.rules[j], ev, t.pfh, t.sda, t.both_shapes, p_) <= tau_) return Recognition::Recognised;
  }
  // Not recognised; with the fusion, whether vision alone would have taken it.
  if (terms_.fused && terms_.visual && ev <= p_.threshold_visual) {
    return Recognition::SeenOnly;
  }
  return Recognition::None;
}

void TemplateStore::restore_decay(double restore, double floor) {
  for (double& d : decay_) d = std::max(floor, d - restore);
}

SigmaEstimate TemplateStore::estimate_sigmas(const MatchParams& p, int max_pairs) const {
  SigmaEstimate out;
  const int n = size();
  if (n < 2) return out;
  const int64_t all = static_cast<int64_t>(n) * (n - 1) / 2;
  const int64_t stride = std::max<int64_t>(1, all / std::max(1, max_pairs));
  struct Acc {
    double s = 0.0, s2 = 0.0;
    int64_t k = 0;
    void add(double x) { s += x; s2 += x * x; ++k; }
    double sd() const { return k < 2 ? 0.0 : std::sqrt(std::max(0.0, (s2 - s * s / k) / (k - 1))); }
  } av, ap, as;
  int64_t idx = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j, ++idx) {
      if (idx % stride != 0) continue;
      const auto iu = static_cast<size_t>(i), ju = static_cast<size_t>(j);
      if (has_visual_[iu] != 0 && has_visual_[ju] != 0) {
        av.add(visual_distance(visual_.row(iu), visual_.row(ju), width_, height_, p.shift_max, p.shift_step,
                               nullptr));
      }
      if (has_tactile_[iu] != 0 && has_tactile_[ju] != 0) {
        ap.add(l1_u16(pfh_.row(iu), pfh_.row(ju), kPfhBins) / 65535.0);
        as.add(sda_distance(sda_.row(iu), sensed_[iu], sda_.row(ju), sensed_[ju]));
      }
      ++out.pairs;
    }
  }
  out.sigma_visual = av.sd();
  out.sigma_pfh = ap.sd();
  out.sigma_sda = as.sd();
  return out;
}

size_t TemplateStore::serialised_bytes() const {
  const auto bytes = [](const auto& v) { return sizeof(uint64_t) + v.size() * sizeof(v[0]); };
  const auto row_bytes = [](const auto& r) {
    return sizeof(uint64_t) + r.elements() * sizeof(typename std::decay_t<decltype(r)>::value_type);
  };
  return 2 * sizeof(int32_t) + row_bytes(visual_) + bytes(visual_mean_) + bytes(has_visual_) + row_bytes(pfh_) + row_bytes(sda_) +
         bytes(has_tactile_) + bytes(num_contacts_) + bytes(pc_) + bytes(decay_) + bytes(sensed_);
}

void TemplateStore::serialise(std::vector<uint8_t>& out) const {
  bin::put<int32_t>(out, width_);
  bin::put<int32_t>(out, height_);
  bin::put_rows(out, visual_);
  bin::put_vec(out, visual_mean_);
  bin::put_vec(out, has_visual_);
  bin::put_rows(out, pfh_);
  bin::put_rows(out, sda_);
  bin::put_vec(out, has_tactile_);
  bin::put_vec(out, num_contacts_);
  bin::put_vec(out, pc_);
  bin::put_vec(out, decay_);
  bin::put_vec(out, sensed_);  // format 5
}

TemplateStore TemplateStore::deserialise(const std::vector<uint8_t>& in, size_t& pos, int width, int height,
                                         uint32_t format_version) {
  TemplateStore s;
  s.width_ = bin::get<int32_t>(in, pos);
  s.height_ = bin::get<int32_t>(in, pos);
  if (s.width_ != width || s.height_ != height) {
    throw std::runtime_error("checkpoint: templates are " + std::to_string(s.width_) + "x" + std::to_string(s.height_) +
                             ", the parameters say " + std::to_string(width) + "x" + std::to_string(height));
  }
  s.visual_ = RowStore<uint8_t>(s.pixels());
  s.blocks_ = RowStore<uint8_t>(s.blocks());
  s.pfh_ = RowStore<uint16_t>(kPfhBins);
  s.sda_ = RowStore<float>(kSdaSize);
  bin::get_rows(in, pos, s.visual_);
  s.visual_mean_ = bin::get_vec<float>(in, pos);
  s.has_visual_ = bin::get_vec<uint8_t>(in, pos);
  bin::get_rows(in, pos, s.pfh_);
  bin::get_rows(in, pos, s.sda_);
  s.has_tactile_ = bin::get_vec<uint8_t>(in, pos);
  s.num_contacts_ = bin::get_vec<int32_t>(in, pos);
  s.pc_ = bin::get_vec<double>(in, pos);
  s.decay_ = bin::get_vec<double>(in, pos);
  const size_t n = s.has_visual_.size();
  if (format_version >= 5) {
    s.sensed_ = bin::get_vec<uint32_t>(in, pos);
  } else {
    s.sensed_.assign(n, kAllWhiskersSensed);
  }
  if (s.visual_.rows() != n || s.visual_mean_.size() != n || s.pfh_.rows() != n || s.sda_.rows() != n ||
      s.has_tactile_.size() != n || s.num_contacts_.size() != n || s.pc_.size() != 3 * n || s.decay_.size() != n ||
      s.sensed_.size() != n) {
    throw std::runtime_error("checkpoint: template arrays disagree in length");
  }
  if (!std::all_of(s.pc_.begin(), s.pc_.end(), [](double v) { return std::isfinite(v); }) ||
      !std::all_of(s.decay_.begin(), s.decay_.end(), [](double v) { return std::isfinite(v); })) {
    throw std::runtime_error("checkpoint: a template's pose-cell coordinates or decay are not finite");
  }
  // A template's mean intensity is in [0, 1] (VisualTemplate::mean); its SDA entries are deflections
  // per second, finite.
  if (!std::all_of(s.visual_mean_.begin(), s.visual_mean_.end(), [](float v) { return v >= 0.0f && v <= 1.0f; })) {
    throw std::runtime_error("checkpoint: a template's visual mean is outside 0..1 (or not a number)");
  }
  for (size_t i = 0; i < n; ++i) {
    const float* sda = s.sda_.row(i);
    if (!std::all_of(sda, sda + kSdaSize, [](float v) { return std::isfinite(v); })) {
      throw std::runtime_error("checkpoint: template " + std::to_string(i) + " has an SDA entry that is not finite");
    }
  }
  for (size_t i = 0; i < n; ++i) block_means(s.visual_.row(i), s.width_, s.height_, s.blocks_.append());
  return s;
}

}  // namespace whiskeye::slam
