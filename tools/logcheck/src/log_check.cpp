#include "whiskeye/logcheck/log_check.h"

#include "whiskeye/common/message_layout.h"

#include <algorithm>
#include <limits>
#include <optional>

namespace whiskeye::logcheck {
namespace {

// b − a, or int64's end in its direction where that does not fit (times on both sides of the range).
int64_t minus_saturating(int64_t b, int64_t a) {
  int64_t d = 0;
  if (__builtin_sub_overflow(b, a, &d)) {
    return b > a ? std::numeric_limits<int64_t>::max() : std::numeric_limits<int64_t>::min();
  }
  return d;
}

}  // namespace

double ChannelStats::rate_hz() const {
  if (count < 2 || max_utime <= min_utime) return 0.0;
  // The span in unsigned arithmetic: it can exceed int64 (−2^63 to 2^63 − 1), never uint64.
  const uint64_t span_us = static_cast<uint64_t>(max_utime) - static_cast<uint64_t>(min_utime);
  return static_cast<double>(count - 1) * 1e6 / static_cast<double>(span_us);
}

uint64_t ChannelStats::sent() const { return static_cast<uint64_t>(count) + static_cast<uint64_t>(lost); }

double ChannelStats::lost_fraction() const {
  return sent() > 0 ? static_cast<double>(lost) / static_cast<double>(sent()) : 0.0;
}

bool ChannelStats::lost_more_than(double max_loss) const { return lost > 0 && lost_fraction() > max_loss; }

void LogCheck::add(std::string_view channel, int64_t utime, std::span<const uint8_t> encoded) {
  auto [it, inserted] = channels_.try_emplace(std::string(channel));
  Channel& c = it->second;
  ChannelStats& s = c.stats;
  if (inserted) {
    s.channel = std::string(channel);
    s.first_utime = s.min_utime = s.max_utime = utime;
    s.sequenced = true;
  } else {
    const int64_t interval = minus_saturating(utime, s.last_utime);
    c.intervals_us.push_back(interval);
    s.max_interval_us = std::max(s.max_interval_us, interval);
  }
  s.last_utime = utime;
  s.min_utime = std::min(s.min_utime, utime);
  s.max_utime = std::max(s.max_utime, utime);
  ++s.count;
  const std::optional<int64_t> seq = sequence_number(encoded);
  if (!seq) {
    s.sequenced = false;
    return;
  }
  c.gaps.add(*seq);
  s.lost = c.gaps.lost();
  s.loss_places = c.gaps.places();
  s.longest_loss = c.gaps.longest();
  s.restarts = c.gaps.restarts();
}

std::vector<ChannelStats> LogCheck::channels() const {
  std::vector<ChannelStats> out;
  for (const auto& [name, c] : channels_) {
    ChannelStats s = c.stats;
    if (!s.sequenced) s.lost = s.loss_places = s.longest_loss = s.restarts = 0;
    if (!c.intervals_us.empty()) {
      std::vector<int64_t> sorted = c.intervals_us;
      std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
      const double median = static_cast<double>(sorted[sorted.size() / 2]);
      for (const int64_t i : c.intervals_us) {
        if (static_cast<double>(i) > gap_factor_ * median && median > 0) ++s.time_gaps;
      }
    }
    out.push_back(std::move(s));
  }
  std::sort(out.begin(), out.end(), [](const ChannelStats& a, const ChannelStats& b) { return a.channel < b.channel; });
  return out;
}

}  // namespace whiskeye::logcheck
