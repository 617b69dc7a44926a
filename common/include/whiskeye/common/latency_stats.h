// Per-interval latency statistics (p50 / p99 / max) for DRIVER_STATUS, with storage reserved up
// front so the real-time thread never allocates.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace whiskeye {

struct LatencySummary {
  double p50_us = 0, p99_us = 0, max_us = 0;
  int64_t count = 0;
};

class LatencyStats {
 public:
  explicit LatencyStats(std::size_t capacity) { values_.reserve(capacity); }
  // Beyond capacity, values are dropped from the percentiles but still count toward max.
  void add(double us) {
    max_ = std::max(max_, us);
    ++count_;
    if (values_.size() < values_.capacity()) values_.push_back(us);
  }
  // Summarises the interval and starts a new one.
  LatencySummary take() {
    LatencySummary s;
    s.count = count_;
    s.max_us = max_;
    if (!values_.empty()) {
      s.p50_us = percentile(0.50);
      s.p99_us = percentile(0.99);
    }
    values_.clear();
    max_ = 0;
    count_ = 0;
    return s;
  }

 private:
  double percentile(double q) {
    const std::size_t k = std::min(values_.size() - 1, static_cast<std::size_t>(q * static_cast<double>(values_.size())));
    std::nth_element(values_.begin(), values_.begin() + static_cast<std::ptrdiff_t>(k), values_.end());
    return values_[k];
  }
  std::vector<double> values_;
  double max_ = 0;
  int64_t count_ = 0;
};

}  // namespace whiskeye
