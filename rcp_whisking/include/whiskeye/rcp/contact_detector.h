// Contact detector: per whisker, deflection magnitude |(x, y)| against a threshold learned from the
// noise floor during the first free-whisking cycles, with hysteresis; contact level 0..1.
// Pure and allocation-free.
#pragma once

#include <whiskeye/rcp/params.h>
#include <whiskeye/rcp/types.h>

namespace whiskeye::rcp {

class ContactDetector {
 public:
  explicit ContactDetector(const DetectorParams& params);

  // Feeds one sample. `learning` says the whiskers are whisking and the noise floor may be learned
  // from this sample; a whisker in contact (default threshold) or within learn_guard_samples after
  // one is not learned from.
  // Invalid whiskers keep their previous state.
  void update(const WhiskerSample& sample, bool learning);
  // Ends the learning phase: thresholds become clamp(noise_factor x noise_quantile of |xy|,
  // threshold_min, threshold_max) for whiskers with enough samples; the others keep the default.
  void finish_learning();
  bool learned() const { return learned_; }

  const PerWhisker<bool>& in_contact() const { return in_contact_; }
  const PerWhisker<double>& level() const { return level_; }
  const PerWhisker<double>& magnitude() const { return magnitude_; }
  const PerWhisker<double>& threshold() const { return threshold_; }
  // Contact onsets (false -> true transitions) since construction, per whisker.
  const PerWhisker<int64_t>& onsets() const { return onsets_; }
  // True for the whiskers whose contact began with the last update().
  const PerWhisker<bool>& onset() const { return onset_; }

  void reset();

 private:
  DetectorParams params_;
  bool learned_ = false;
  PerWhisker<double> threshold_{};
  PerWhisker<bool> in_contact_{};
  PerWhisker<bool> onset_{};
  PerWhisker<double> level_{};
  PerWhisker<double> magnitude_{};
  PerWhisker<int64_t> onsets_{};
  // Histogram of the free-whisking magnitude over [0, threshold_max / noise_factor); larger values
  // only count (the quantile needs to know they are above it, not where).
  static constexpr int kBins = 256;
  double bin_width_ = 1.0;
  PerWhisker<int64_t> n_{};
  PerWhisker<int64_t> above_{};
  PerWhisker<int64_t> quiet_{};  // samples since the whisker was last in contact
  std::array<std::array<int32_t, kBins>, kNumWhiskers> histogram_{};
};

}  // namespace whiskeye::rcp
