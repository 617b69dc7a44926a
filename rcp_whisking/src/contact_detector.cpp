// Contact detector (see contact_detector.h).
#include <whiskeye/rcp/contact_detector.h>

#include <algorithm>
#include <cmath>

namespace whiskeye::rcp {

ContactDetector::ContactDetector(const DetectorParams& params) : params_(params) { reset(); }

void ContactDetector::reset() {
  learned_ = false;
  threshold_.fill(params_.default_threshold);
  in_contact_.fill(false);
  onset_.fill(false);
  level_.fill(0.0);
  magnitude_.fill(0.0);
  onsets_.fill(0);
  n_.fill(0);
  mean_.fill(0.0);
  m2_.fill(0.0);
}

void ContactDetector::update(const WhiskerSample& sample, bool learning) {
  const bool learn = learning && !learned_;
  for (int w = 0; w < kNumWhiskers; ++w) {
    onset_[w] = false;
    if (!sample.valid[w]) continue;
    const double x = sample.deflection_x[w];
    const double y = sample.deflection_y[w];
    const double m = std::sqrt(x * x + y * y);
    magnitude_[w] = m;
    // A sample above the default threshold is probably a contact, not noise: never learn from it.
    if (learn && m < params_.default_threshold) {
      ++n_[w];
      const double delta = m - mean_[w];
      mean_[w] += delta / static_cast<double>(n_[w]);
      m2_[w] += delta * (m - mean_[w]);
    }
    const double th = threshold_[w];
    const bool was = in_contact_[w];
    const bool now = was ? m >= params_.release_ratio * th : m > th;
    in_contact_[w] = now;
    if (now && !was) {
      onset_[w] = true;
      ++onsets_[w];
    }
    level_[w] = now ? std::clamp(params_.contact_gain * (m - th), 0.0, 1.0) : 0.0;
  }
}

void ContactDetector::finish_learning() {
  if (learned_) return;
  learned_ = true;
  for (int w = 0; w < kNumWhiskers; ++w) {
    if (n_[w] < params_.learn_min_samples) continue;
    const double sigma = std::sqrt(m2_[w] / static_cast<double>(n_[w] - 1));
    threshold_[w] = std::clamp(mean_[w] + params_.noise_k_sigma * sigma, params_.threshold_min, params_.threshold_max);
  }
}

}  // namespace whiskeye::rcp
