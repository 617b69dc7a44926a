// Template memory and matching (paper Algorithm 1 "COMP"): every stored template is one whisk
// cycle's visual and tactile parts under one id. For the current template
//   ε_i = V_i/σ_V + PFH_i/σ_PFH + SDA_i/σ_SDA
// where V_i is the minimum over column shifts ±shift_max of the mean absolute difference over the
// overlap (intensities in [0, 1]) — computed afresh for every stored template i — and PFH_i, SDA_i
// are L1 distances. Only the terms in use this cycle count (mode ∩ senses present); a stored
// template that lacks a part in use is not a candidate. The result is the argmin over templates;
// with Terms::fused (ViTa, both senses) the fusion's rules of MatchParams::tactile_veto instead.
//
// Each template's parts are contiguous (one byte per visual pixel, 16 bits per PFH bin, one float per
// SDA entry), the templates in chunks of 256 that never move:
// 64×40 + 125·2 + 24·4 = 2,906 bytes per template, plus 46 bytes of bookkeeping (visual mean 4, the
// two has-part flags 2, contact count 4, sensed whiskers 4, pose-cell x, y, θ 24, decay 8): 2,952
// bytes, also what a checkpoint holds per template (TemplateMatch.StoresATemplateInAtMostThreeKilobytes). In memory only, a 4-row
// block-mean copy of the visual part for the matcher's lower bound: 640 bytes at 64×40, so 3,592
// bytes per template in memory, 35.9 MB at 10,000 templates.
#pragma once

#include "whiskeye/common/params.h"
#include "whiskeye/slam/row_store.h"
#include "whiskeye/slam/tactile_template.h"
#include "whiskeye/slam/types.h"
#include "whiskeye/slam/visual_template.h"

#include <cstdint>
#include <vector>

namespace whiskeye::slam {

struct MatchParams {
  int shift_max = 5;   // template columns, each way
  int shift_step = 1;
  // σ's: the scale of each term (the paper's α = 1/σ_V, β = 1/σ_PFH, γ = 1/σ_SDA). Units: V is a
  // mean absolute intensity difference in [0, 1]; PFH an L1 distance of pair fractions in [0, 2];
  // SDA an L1 distance of slopes (deflection/s) summed over 24 whiskers. estimate_sigmas() gives
  // data-driven values.
  double sigma_visual = 0.25;
  double sigma_pfh = 1.5;
  double sigma_sda = 15.0;
  // Match if ε ≤ threshold; one threshold per combination of terms in use this cycle, as a
  // visual-only ε and a three-term ε have different scales.
  double threshold_visual = 0.1;
  double threshold_tactile = 0.2;
  double threshold_vita = 0.3;
  // The fusion (Terms::fused, a ViTa cycle with both senses): touch adds evidence where it has some
  // and vetoes only where it clearly disagrees. The match is
  //   vision's choice: the least V/σ_V ≤ threshold_visual among the templates whose tactile terms
  //   (PFH/σ_PFH + SDA/σ_SDA) are ≤ tactile_veto — touch does not object; reported on threshold_vita's
  //   scale (V/σ_V · threshold_vita/threshold_visual);
  //   and only where there is none, both senses' evidence: the least ε = V/σ_V + PFH/σ_PFH + SDA/σ_SDA
  //   ≤ threshold_vita among the templates that, like this cycle, felt a shape (a PFH) and whose
  //   V/σ_V ≤ threshold_visual_touched: a clear touch lets a view a little beyond vision's own
  //   threshold count, never any view.
  // A place touched at another phase of the whisk differs by 0.2-0.35 in the tactile terms; a box
  // from a post, or a contact from none (an empty PFH is 1/σ_PFH from any other), by more.
  // 0: the paper's sum ε ≤ threshold_vita for a cycle that touched something; one that touched
  // nothing is decided by vision among the templates that touched nothing either.
  double tactile_veto = 0.5;
  double threshold_visual_touched = 0.2;
  // Skip templates whose mean intensity differs by more than this (≥ 1: never skip). Visual terms
  // only; with global normalisation all means are equal, so it is off by default.
  double prefilter_mean_diff = 1.0;
  // Exact lower-bound pruning (see match()): the result is bit-identical either way, so it is not
  // a configuration key; off only to measure the plain scan (benchmarks) and to test the identity.
  bool lower_bound_prefilter = true;
};
void load(const ParamNode& node, MatchParams& p);

// Which terms a comparison uses.
struct Terms {
  bool visual = false;
  bool tactile = false;
  // ViTa's fusion of both senses (MatchParams::tactile_veto): the visual and tactile terms are both
  // computed and combined by the rules there; BestMatch::error is then on threshold_vita's scale.
  bool fused = false;
};

// The current cycle's template (parts absent are nullptr).
struct Query {
  const VisualTemplate* visual = nullptr;
  const TactileTemplate* tactile = nullptr;
};

struct BestMatch {
  int id = -1;  // -1: no candidate
  double error = 0.0, visual = 0.0, pfh = 0.0, sda = 0.0;  // divided by σ
  int shift = 0;
};

struct SigmaEstimate {
  double sigma_visual = 0.0, sigma_pfh = 0.0, sigma_sda = 0.0;  // 0: not enough data for that term
  int pairs = 0;
};

class TemplateStore {
 public:
  TemplateStore() = default;
  TemplateStore(int visual_width, int visual_height);

  int size() const { return static_cast<int>(has_visual_.size()); }
  int visual_width() const { return width_; }
  int visual_height() const { return height_; }

  // Appends; returns the new id. Parts absent are stored as zeros and flagged missing.
  int add(const Query& q, double pc_x, double pc_y, double pc_theta);

  // The argmin of ε over the candidates (the first one on ties); with terms.fused, the fusion's
  // rules (MatchParams::tactile_veto), each rule's argmin found in the same pass. With
  // p.lower_bound_prefilter, a template's visual term is first bounded from below on a coarse copy
  // (each column's rows in blocks of 4, floored block means): per block of k = 4 pixels
  // Σ|a − b| ≥ k·|ā − b̄| − (k − 1), so
  //   k·SAD(coarse overlap of shift s) − (k − 1)·(blocks in it) ≤ SAD_s,
  // a quarter of the work. A template whose error computed with that bound (same floating-point
  // operations, all monotone) is already ≥ the best so far, for every rule, cannot win and is
  // skipped; within a compared template, a shift whose bound cannot beat its best shift so far is
  // skipped. Neither changes the result.
  BestMatch match(const Query& q, const Terms& terms, const MatchParams& p) const;

  // Whether stored template `id` is one `q` would be recognised as by match()'s rules (the same
  // terms, rules and prefilter) within `tau`: not only the best template but any that passes; with
  // Terms::fused, SeenOnly for one that vision alone would take (V ≤ threshold_visual) where touch
  // objects. The localiser asks it of the templates around each candidate place. One per cycle: the
  // query is prepared once.
  class Recogniser {
   public:
    Recogniser(const TemplateStore& store, const Query& q, const Terms& terms, const MatchParams& p, double tau);
    Recognition operator()(int id) const;

   private:
    const TemplateStore& store_;
    Query q_;
    Terms terms_;
    MatchParams p_;
    double tau_;
    std::vector<uint8_t> cur_;  // the query's visual template, column-major
  };

  bool has_visual(int id) const { return has_visual_[static_cast<size_t>(id)] != 0; }
  bool has_tactile(int id) const { return has_tactile_[static_cast<size_t>(id)] != 0; }
  int num_contacts(int id) const { return num_contacts_[static_cast<size_t>(id)]; }
  // The whiskers that had data when the template was made (TactileTemplate::sensed).
  uint32_t sensed(int id) const { return sensed_[static_cast<size_t>(id)]; }
  // Column-major (x·height + y): see visual_distance().
  const uint8_t* visual(int id) const { return visual_.row(static_cast<size_t>(id)); }
  const uint16_t* pfh(int id) const { return pfh_.row(static_cast<size_t>(id)); }
  const float* sda(int id) const { return sda_.row(static_cast<size_t>(id)); }
  // Pose-cell coordinates (cells) at creation: where a match injects energy.
  double pc_x(int id) const { return pc_[static_cast<size_t>(id) * 3]; }
  double pc_y(int id) const { return pc_[static_cast<size_t>(id) * 3 + 1]; }
  double pc_theta(int id) const { return pc_[static_cast<size_t>(id) * 3 + 2]; }

  // Injection decay, after OpenRatSLAM's rule with two differences: each match of a template adds
  // `active` (also while it is among the newest, which inject nothing), and every cycle all templates
  // relax by `restore` towards `floor` (0 in VitaSlam, where OpenRatSLAM relaxes to `active`), so a
  // first match injects inject·(30 − e^{1.2·active})/30 and a run of matches fades a cycle later.
  double decay(int id) const { return decay_[static_cast<size_t>(id)]; }
  void bump_decay(int id, double active) { decay_[static_cast<size_t>(id)] += active; }
  void restore_decay(double restore, double floor);

  // Standard deviation of each raw term (not divided by σ) over pairs of stored templates.
  SigmaEstimate estimate_sigmas(const MatchParams& p, int max_pairs = 20000) const;

  // Raw (un-normalised) visual term between two COLUMN-MAJOR images (the stored layout): the
  // minimum over shifts s = 0, ±step, ... ±shift_max of the mean |cur(c) − stored(c − s)| over the
  // overlapping columns, in [0, 1]; exposed for tests and the benchmark.
  static double visual_distance(const uint8_t* cur, const uint8_t* stored, int w, int h, int shift_max, int shift_step,
                                int* best_shift);

  void serialise(std::vector<uint8_t>& out) const;
  size_t serialised_bytes() const;  // what serialise() appends
  // Reads what serialise() wrote at `pos`, advancing it; throws std::runtime_error on bad data, and
  // on visual templates of another size than width x height before it allocates for them. A
  // checkpoint before format 5 holds no sensed whiskers: every template reads as fully sensed.
  static TemplateStore deserialise(const std::vector<uint8_t>& in, size_t& pos, int width, int height,
                                   uint32_t format_version);

  bool operator==(const TemplateStore&) const = default;

 private:
  size_t pixels() const { return static_cast<size_t>(width_) * static_cast<size_t>(height_); }
  size_t blocks() const;
  // The one routine of each per-template quantity that match() and the Recogniser share, so that
  // they agree bit for bit: the query's check (std::invalid_argument for a visual template of
  // another size), the σ scaling, whether a stored template can be compared at all (the senses it
  // has, the visual mean prefilter), and the tactile terms.
  struct TermScale {
    double visual = 1.0, pfh = 1.0, sda = 1.0;  // 1 / σ of each term (the PFH's over its 16-bit range)
  };
  static TermScale scale_of(const MatchParams& p);
  void check_query(const Query& q, const Terms& terms, const char* who) const;
  bool comparable(size_t i, const Query& q, const Terms& terms, const MatchParams& p) const;
  struct TactileTerms {
    double pfh = 0.0, sda = 0.0;
    bool both_shapes = false;  // both felt a shape: touch may add evidence
  };
  TactileTerms tactile_terms(size_t i, const Query& q, const TermScale& scale) const;

  int width_ = 0;
  int height_ = 0;
  // Per template, in chunks that never move (row_store.h): adding a template copies nothing.
  RowStore<uint8_t> visual_;
  RowStore<uint8_t> blocks_;  // blocks() per template: 4-row block means of visual_ (not serialised)
  std::vector<float> visual_mean_;
  std::vector<uint8_t> has_visual_;
  RowStore<uint16_t> pfh_;
  RowStore<float> sda_;
  std::vector<uint8_t> has_tactile_;
  std::vector<int32_t> num_contacts_;
  std::vector<uint32_t> sensed_;
  std::vector<double> pc_;
  std::vector<double> decay_;
};

}  // namespace whiskeye::slam
