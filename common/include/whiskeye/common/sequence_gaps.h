// Messages missing between sequence numbers: the one rule for "lost on the way", used by
// whiskeye-logcheck (per channel of a recording) and slamd (per input, SLAM_STATUS.input_gaps).
// A number above the one before + 1: the ones between were lost. A number not above the one before:
// the sender restarted (or repeated itself); not a loss, and counting goes on from it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>

namespace whiskeye {

class SequenceGaps {
 public:
  // Takes the next message's number; returns how many were missing just before it (0: none).
  int64_t add(int64_t seq) {
    int64_t missing = 0;
    if (last_) {
      if (seq <= *last_) {
        ++restarts_;
      } else if (seq > *last_ + 1) {
        // Computed without overflow: both are int64 and seq > last + 1.
        missing = static_cast<int64_t>(static_cast<uint64_t>(seq) - static_cast<uint64_t>(*last_) - 1);
        lost_ += missing;
        ++places_;
        longest_ = std::max(longest_, missing);
      }
    }
    last_ = seq;
    return missing;
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
