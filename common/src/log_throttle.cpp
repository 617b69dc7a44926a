#include "whiskeye/common/log_throttle.h"

namespace whiskeye {

std::optional<std::string> LogThrottle::admit(const std::string& key, const std::string& line, int64_t now_us) {
  {
    std::lock_guard lock(mutex_);
    const auto [it, first] = keys_.try_emplace(key);
    State& s = it->second;
    // A clock that went back (another clock's time, a test) restarts the period rather than muting it.
    if (!first && now_us >= s.last_logged_us && now_us - s.last_logged_us < period_us_) {
      ++s.suppressed;
      return std::nullopt;
    }
  }
  return force(key, line, now_us);
}

std::string LogThrottle::force(const std::string& key, const std::string& line, int64_t now_us) {
  std::lock_guard lock(mutex_);
  State& s = keys_[key];
  std::string out = line;
  if (s.suppressed > 0) {
    out += "; " + std::to_string(s.suppressed) + " more like it suppressed in the last " +
           std::to_string((now_us - s.last_logged_us) / 1'000'000) + " s";
  }
  s.last_logged_us = now_us;
  s.suppressed = 0;
  return out;
}

int64_t LogThrottle::suppressed(const std::string& key) const {
  std::lock_guard lock(mutex_);
  const auto it = keys_.find(key);
  return it == keys_.end() ? 0 : it->second.suppressed;
}

}  // namespace whiskeye
