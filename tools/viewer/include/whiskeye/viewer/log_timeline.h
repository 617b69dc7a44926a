// A recorded LCM log as a timeline the page's slider moves along: seek(t) gives the viewer's state
// as it was once every message logged at or before t had arrived. Events are ordered by their log
// time (stable: file order among equal times), so "at or before t" is a prefix of the log and the
// state at t does not depend on which times were asked for before. Moving forward applies only the
// events since the last seek; moving back starts over. Of the latest-only channels (a whole map, a
// frame, a whisk cycle: is_latest_only()) only the newest message before t is decoded.
// A log file is read once to index it (where each event is); an event's bytes are read again with
// pread() when a seek applies it, so the file may change under the viewer (a replay writing into it)
// without harm: a file that got shorter or was rewritten since it was indexed is a LogChanged error,
// never a fault on a mapping.
#pragma once

#include "whiskeye/viewer/viewer_state.h"

#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace whiskeye::viewer {

// The log file changed since it was indexed: what() says how.
struct LogChanged : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class LogTimeline {
 public:
  explicit LogTimeline(ViewerParams params = {});
  ~LogTimeline();
  LogTimeline(const LogTimeline&) = delete;
  LogTimeline& operator=(const LogTimeline&) = delete;
  // Adds one event held in memory; `owner` keeps `data` valid as long as the timeline lives. Events
  // of channels the viewer does not show are not kept.
  void add(int64_t utime, std::string_view channel, std::span<const uint8_t> data, std::shared_ptr<const void> owner);
  // Indexes every event of an LCM log file (read once, in order; nothing is kept but where each
  // event is). Throws std::runtime_error naming the file when it cannot be read or is not a regular
  // file; damage() says what was skipped.
  static std::unique_ptr<LogTimeline> from_file(const std::string& path, ViewerParams params = {});
  const std::string& damage() const { return damage_; }
  // Empty while the file is as indexed; else why not (then every seek throws LogChanged with it).
  const std::string& changed() const { return changed_; }

  std::size_t events() const { return events_.size(); }
  int64_t start_utime() const;  // 0 for an empty log
  int64_t end_utime() const;

  // The state at `t`: every kept event with utime <= t applied. Throws LogChanged when the file is
  // no longer what was indexed (checked at every seek and every event read).
  const ViewerState& seek(int64_t t);
  const ViewerState& state() const { return state_; }

 private:
  struct Event {
    int64_t utime;
    std::string_view channel;  // one of the shown channels' names (static)
    std::span<const uint8_t> data;
    std::shared_ptr<const void> owner;  // null for an event in the file
    uint64_t offset = 0;                // in the file: where its header starts
    uint32_t size = 0;                  // in the file: its data's length
  };
  struct File;  // the indexed file: descriptor, size and time it had (log_timeline.cpp)
  void sort();
  void apply(const Event& e);
  void check_unchanged();
  [[noreturn]] void fail(const std::string& why);

  ViewerParams params_;
  std::vector<Event> events_;
  bool sorted_ = true;
  ViewerState state_;
  std::size_t applied_ = 0;  // events_[0, applied_) are in state_
  int64_t at_ = INT64_MIN;   // the time of the last seek
  std::string damage_;
  std::string changed_;
  std::unique_ptr<File> file_;
};

}  // namespace whiskeye::viewer
