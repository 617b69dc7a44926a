// A recorded log as a timeline (log_timeline.h).
#include "whiskeye/viewer/log_timeline.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"

#include <algorithm>
#include <map>

namespace whiskeye::viewer {

namespace {

bool shown(std::string_view channel) {
  for (const char* c : {channels::kVitaMap, channels::kVitaPose, channels::kVitaEvent, channels::kVitaMatch,
                        channels::kDriverStatus, channels::kSlamStatus, channels::kWhiskCycle, channels::kCamera}) {
    if (channel == c) return true;
  }
  return false;
}

}  // namespace

void LogTimeline::add(int64_t utime, std::string_view channel, std::span<const uint8_t> data,
                      std::shared_ptr<const void> owner) {
  if (!shown(channel)) return;
  if (!events_.empty() && utime < events_.back().utime) sorted_ = false;
  events_.push_back({utime, channel, data, std::move(owner)});
}

std::unique_ptr<LogTimeline> LogTimeline::from_file(const std::string& path, ViewerParams params) {
  auto timeline = std::make_unique<LogTimeline>(params);
  LogReader reader(path);
  LogReader::EventView ev;
  // The channel names are views into the mapped file too, kept alive by each event's owner.
  while (reader.next(ev)) timeline->add(ev.utime, ev.channel, ev.data, ev.owner);
  timeline->damage_ = reader.damage().summary();
  timeline->sort();
  return timeline;
}

void LogTimeline::sort() {
  if (sorted_) return;
  std::stable_sort(events_.begin(), events_.end(), [](const Event& a, const Event& b) { return a.utime < b.utime; });
  sorted_ = true;
}

int64_t LogTimeline::start_utime() const { return events_.empty() ? 0 : std::min_element(events_.begin(), events_.end(), [](const Event& a, const Event& b) { return a.utime < b.utime; })->utime; }

int64_t LogTimeline::end_utime() const { return events_.empty() ? 0 : std::max_element(events_.begin(), events_.end(), [](const Event& a, const Event& b) { return a.utime < b.utime; })->utime; }

const ViewerState& LogTimeline::seek(int64_t t) {
  sort();
  if (t < at_) {
    state_ = ViewerState(params_);
    applied_ = 0;
  }
  at_ = t;
  const auto end = static_cast<std::size_t>(
      std::upper_bound(events_.begin(), events_.end(), t, [](int64_t v, const Event& e) { return v < e.utime; }) -
      events_.begin());
  // The newest event of each latest-only channel in the range is applied last, in log order; the
  // ones before it are only counted (each replaces everything before it).
  std::map<std::string_view, std::size_t> newest;
  for (std::size_t i = applied_; i < end; ++i) {
    if (is_latest_only(events_[i].channel)) newest[events_[i].channel] = i;
  }
  std::vector<std::size_t> last;
  for (const auto& [channel, i] : newest) last.push_back(i);
  std::sort(last.begin(), last.end());
  for (std::size_t i = applied_; i < end; ++i) {
    const Event& e = events_[i];
    if (!is_latest_only(e.channel)) {
      state_.apply(e.channel, e.utime, e.data, e.owner);
    } else if (!std::binary_search(last.begin(), last.end(), i)) {
      state_.skip(e.channel, e.utime);
    }
  }
  for (std::size_t i : last) state_.apply(events_[i].channel, events_[i].utime, events_[i].data, events_[i].owner);
  applied_ = std::max(applied_, end);
  state_.set_now(t);
  return state_;
}

}  // namespace whiskeye::viewer
