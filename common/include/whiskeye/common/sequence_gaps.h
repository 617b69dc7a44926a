// Messages missing between sequence numbers: the one rule for "lost on the way", used by
// whiskeye-logcheck (per channel of a recording) and slamd (per input, SLAM_STATUS.input_gaps).
// A number above the one before + 1: the ones between were lost. A number not above the one before:
// the sender restarted (or repeated itself); not a loss, and counting goes on from it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>

namespace whiskeye {

// total + n for counts (both ≥ 0), at most the largest int64: a count of lost messages saturates.
inline int64_t add_count_saturating(int64_t total, int64_t n) {
  return total > std::numeric_limits<int64_t>::max() - n ? std::numeric_limits<int64_t>::max() : total + n;
}

class SequenceGaps {
 public:
  static constexpr int64_t kMax = std::numeric_limits<int64_t>::max();

  // Takes the next message's number; returns how many were missing just before it (0: none). The
  // count between two numbers can exceed int64 (−2^63 then 2^63 − 1): it and the totals saturate
  // at the largest int64 instead of overflowing.
  int64_t add(int64_t seq) {
    int64_t missing = 0;
    if (last_) {
      if (seq <= *last_) {
        ++restarts_;
      } else if (seq - 1 > *last_) {  // seq > last + 1, without computing last + 1
        const uint64_t between = static_cast<uint64_t>(seq) - static_cast<uint64_t>(*last_) - 1;
        missing = between > static_cast<uint64_t>(kMax) ? kMax : static_cast<int64_t>(between);
        lost_ = add_count_saturating(lost_, missing);
        ++places_;
        longest_ = std::max(longest_, missing);
      }
    }
    last_ = seq;
    return missing;
  }
  // A message that arrived but was refused (a bad value, a time jump): when it is the next number
  // it is no gap, and the following one must not be counted as missing it. Any other number (a
  // stale copy, or the corrupt field that got it refused) changes nothing.
  void arrived(int64_t seq) {
    if (last_ && *last_ != kMax && seq == *last_ + 1) last_ = seq;
  }
  int64_t lost() const { return lost_; }          // messages missing in all
  int64_t places() const { return places_; }      // places where messages were missing
  int64_t longest() const { return longest_; }    // the most missing in a row
  int64_t restarts() const { return restarts_; }  // numbers not above the one before

 private:
  std::optional<int64_t> last_;
  int64_t lost_ = 0, places_ = 0, longest_ = 0, restarts_ = 0;
};

}  // namespace whiskeye
