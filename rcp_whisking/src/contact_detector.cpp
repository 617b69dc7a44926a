// Contact detector (see contact_detector.h).
#include <whiskeye/rcp/contact_detector.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace whiskeye::rcp {

ContactDetector::ContactDetector(const DetectorParams& params)
    : params_(params), bin_width_(params.threshold_max / params.noise_factor / kBins) {
  reset();
}

void ContactDetector::reset() {
  learned_ = false;
  threshold_.fill(params_.default_threshold);
  in_contact_.fill(false);
  onset_.fill(false);
  level_.fill(0.0);
  magnitude_.fill(0.0);
  onsets_.fill(0);
  n_.fill(0);
  above_.fill(0);
  quiet_.fill(std::numeric_limits<int64_t>::max() / 2);  // never in contact yet
  for (auto& h : histogram_) h.fill(0);
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
    const double th = threshold_[w];
    const bool was = in_contact_[w];
    const bool now = was ? m >= params_.release_ratio * th : m > th;
    in_contact_[w] = now;
    if (now && !was) {
      onset_[w] = true;
      ++onsets_[w];
    }
    quiet_[w] = now ? 0 : quiet_[w] + 1;
    // Learn the floor only from samples away from any contact seen with the default threshold:
    // not while in contact, nor in the release tail just after. The rising edge before a contact
    // is detected remains; the quantile statistic is robust to it.
    if (learn && quiet_[w] > params_.learn_guard_samples) {
      ++n_[w];
      const auto bin = static_cast<int64_t>(m / bin_width_);
      if (bin < kBins) {
        ++histogram_[w][static_cast<std::size_t>(bin)];
      } else {
        ++above_[w];
      }
    }
    level_[w] = now ? std::clamp(params_.contact_gain * (m - th), 0.0, 1.0) : 0.0;
  }
}

void ContactDetector::finish_learning() {
  if (learned_) return;
  learned_ = true;
  for (int w = 0; w < kNumWhiskers; ++w) {
    if (n_[w] < params_.learn_min_samples) continue;
    // Upper edge of the bin where the cumulative count reaches the quantile (conservative).
    const auto rank = static_cast<int64_t>(std::ceil(params_.noise_quantile * static_cast<double>(n_[w])));
    int64_t cumulative = 0;
    double quantile = static_cast<double>(kBins) * bin_width_;  // in the overflow: threshold_max
    for (int b = 0; b < kBins; ++b) {
      cumulative += histogram_[w][static_cast<std::size_t>(b)];
      if (cumulative >= rank) {
        quantile = static_cast<double>(b + 1) * bin_width_;
        break;
      }
    }
    threshold_[w] = std::clamp(params_.noise_factor * quantile, params_.threshold_min, params_.threshold_max);
  }
}

}  // namespace whiskeye::rcp
