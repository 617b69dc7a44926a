// What a recording lost: per channel, how many messages, at what rate, and — on every channel whose
// messages carry a sequence number (whiskeye::sequence_number, message_layout.h) — how many never
// reached the log (the stock lcm-logger drops under load and says nothing). Pure: events in, statistics out; whiskeye-logcheck reads the file.
#pragma once

#include "whiskeye/common/sequence_gaps.h"

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace whiskeye::logcheck {

struct ChannelStats {
  std::string channel;
  int64_t count = 0;
  int64_t first_utime = 0;
  int64_t last_utime = 0;
  int64_t min_utime = 0;        // the earliest and latest event times (a clock may jump back)
  int64_t max_utime = 0;
  int64_t max_interval_us = 0;  // longest time between two consecutive events (saturates at int64's end)
  int64_t time_gaps = 0;        // intervals longer than gap_factor × the channel's median interval
  bool sequenced = false;       // every message carried a sequence number
  int64_t lost = 0;             // messages missing by the sequence numbers
  int64_t loss_places = 0;      // places where messages were missing
  int64_t longest_loss = 0;     // the most missing in a row
  int64_t restarts = 0;         // a sequence number not above the one before (a sender restarted)
  double rate_hz() const;  // events per second over [min_utime, max_utime]; 0 with fewer than 2 or no span
  // count + lost: the messages sent. Unsigned: both are int64, their sum (a saturated loss) is not.
  uint64_t sent() const;
  double lost_fraction() const;  // lost / sent()
  // More than `max_loss` (a fraction) of the messages lost; with max_loss 0, any loss at all.
  bool lost_more_than(double max_loss) const;
};

class LogCheck {
 public:
  // A time gap is an interval longer than `gap_factor` × the channel's median interval.
  explicit LogCheck(double gap_factor = 3.0) : gap_factor_(gap_factor) {}
  void add(std::string_view channel, int64_t utime, std::span<const uint8_t> encoded);
  // Every channel seen, by name.
  std::vector<ChannelStats> channels() const;

 private:
  struct Channel {
    ChannelStats stats;
    SequenceGaps gaps;
    std::vector<int64_t> intervals_us;
  };
  double gap_factor_;
  std::unordered_map<std::string, Channel> channels_;
};

}  // namespace whiskeye::logcheck
