// Rate limit for repeated log lines: a journal on the robot's eMMC is not free, and 2,000 undecodable
// messages must not become 2,000 lines. Pure (time is an argument) and thread-safe.
//
// Lines are grouped by a key (what repeats: "decode WHISK_CYCLE", "checkpoint"). The first line of a
// key is logged; after it, at most one per `period_us`; the one logged after some were held back says
// how many ("; 1999 more like it suppressed in the last 10 s"), so nothing is lost but the words.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace whiskeye {

class LogThrottle {
 public:
  explicit LogThrottle(int64_t period_us = 10'000'000) : period_us_(period_us) {}

  // The line to log now (with the count of those suppressed since the last one), or nothing.
  std::optional<std::string> admit(const std::string& key, const std::string& line, int64_t now_us);
  // The same for a line that must be logged whatever the period (the first of a new burst): the line
  // with the count suppressed so far, and the period starts again.
  std::string force(const std::string& key, const std::string& line, int64_t now_us);
  // Lines of `key` held back since the last one logged.
  int64_t suppressed(const std::string& key) const;

 private:
  struct State {
    int64_t last_logged_us = 0;
    int64_t suppressed = 0;
  };
  int64_t period_us_;
  mutable std::mutex mutex_;
  std::map<std::string, State> keys_;
};

}  // namespace whiskeye
