// A recorded LCM log as a timeline the page's slider moves along: seek(t) gives the viewer's state
// as it was once every message logged at or before t had arrived. Events are ordered by their log
// time (stable: file order among equal times), so "at or before t" is a prefix of the log and the
// state at t does not depend on which times were asked for before. Moving forward applies only the
// events since the last seek; moving back starts over. Of the latest-only channels (a whole map, a
// frame, a whisk cycle: is_latest_only()) only the newest message before t is decoded.
#pragma once

#include "whiskeye/viewer/viewer_state.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace whiskeye::viewer {

class LogTimeline {
 public:
  explicit LogTimeline(ViewerParams params = {}) : params_(params), state_(params) {}
  // Adds one event; `owner` keeps `channel` and `data` valid as long as the timeline lives. Events
  // of channels the viewer does not show are not kept.
  void add(int64_t utime, std::string_view channel, std::span<const uint8_t> data, std::shared_ptr<const void> owner);
  // Reads every event of an LCM log file (memory-mapped: views, no copies). Throws
  // std::runtime_error naming the file when it cannot be read; damage() says what was skipped.
  static std::unique_ptr<LogTimeline> from_file(const std::string& path, ViewerParams params = {});
  const std::string& damage() const { return damage_; }

  std::size_t events() const { return events_.size(); }
  int64_t start_utime() const;  // 0 for an empty log
  int64_t end_utime() const;

  // The state at `t`: every kept event with utime <= t applied.
  const ViewerState& seek(int64_t t);
  const ViewerState& state() const { return state_; }

 private:
  struct Event {
    int64_t utime;
    std::string_view channel;
    std::span<const uint8_t> data;
    std::shared_ptr<const void> owner;
  };
  void sort();

  ViewerParams params_;
  std::vector<Event> events_;
  bool sorted_ = true;
  ViewerState state_;
  std::size_t applied_ = 0;  // events_[0, applied_) are in state_
  int64_t at_ = INT64_MIN;   // the time of the last seek
  std::string damage_;
};

}  // namespace whiskeye::viewer
