// Reading an LCM log file (the format lcm-logger writes, lcm/eventlog.c) directly: its event header,
// and LogReader, which hands out the events in file order as views without copying, skipping and
// reporting damage. No LCM library: the format is read here.
#pragma once

#include "whiskeye/common/big_endian.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace whiskeye {

// An LCM log event's header: sync word, event number, time, channel length, data length, all
// big-endian; then the channel name and the data.
namespace lcm_log {
inline constexpr uint32_t kSyncWord = 0xEDA1DA01u;
inline constexpr std::size_t kEventHeaderBytes = 4 + 8 + 8 + 4 + 4;
struct EventHeader {
  uint32_t sync = 0;
  int64_t utime = 0;  // the logger's receive time
  int32_t channel_bytes = 0;
  int32_t data_bytes = 0;
};
// The header whose kEventHeaderBytes bytes start at `h`.
inline EventHeader read_event_header(const uint8_t* h) {
  return EventHeader{static_cast<uint32_t>(read_be_i32(h)), read_be_i64(h + 12), read_be_i32(h + 20), read_be_i32(h + 24)};
}
}  // namespace lcm_log

// One event of an LCM log file.
struct LogEvent {
  int64_t utime = 0;  // the logger's receive time
  std::string channel;
  std::vector<uint8_t> data;
};

// Reads an LCM log (as written by lcm-logger) directly, in file order, in one of two ways (Access):
// - kMapped (the default): the file is memory-mapped and events are views into the mapping; pages of
//   payloads nobody reads are never loaded, and a view costs nothing to keep (the viewer's timeline
//   keeps one of every event).
// - kStreamed: the file is read in order with pread() into chunks of `chunk_bytes` (a larger event
//   gets a chunk of its size); a view keeps its chunk, and chunks nobody holds are reused. Every
//   byte is copied once, read or not. For one pass that keeps few views (a replay, a check): on some
//   machines mapping a page costs more than copying it (docs/performance.md, "### Replay"). An error
//   reading the file, or the file getting shorter while read, throws std::runtime_error naming it.
// Every event header is checked (sync word, lengths within the file); damage is skipped and reported by
// damage(), never a silent early end. An event time out of line with both neighbours while they
// agree with each other (more than kMaxTimeJumpUs from each: a flipped bit) is damage too: the event
// is delivered with the time of the one before (the first event: of the one after) and counted, so
// one wild time does not become months of data time. A clock step is not (the events after it agree
// with it), nor a lone message in a pause (its neighbours do not agree); the first and last events,
// with one neighbour, count as wild only more than kMaxEdgeTimeJumpUs from it.
class LogReader {
 public:
  enum class Access { kMapped, kStreamed };
  static constexpr std::size_t kDefaultChunkBytes = 128 * 1024;
  // Throws std::runtime_error naming the file if it cannot be opened. A damaged log (a corrupt
  // event header, a last event cut off by a crash or a full disk) does not throw: next() skips what
  // cannot be read, resynchronising on the next event's sync word as LCM's own reader does, and
  // damage() says what was skipped, where first.
  explicit LogReader(const std::string& path, Access access = Access::kMapped,
                     std::size_t chunk_bytes = kDefaultChunkBytes);
  // How far an event's time may lie from both neighbours before it is taken as damage (slamd's
  // max_jump_s default).
  static constexpr int64_t kMaxTimeJumpUs = 10'000'000;
  static constexpr int64_t kMaxEdgeTimeJumpUs = 86'400'000'000;  // a day
  // Reads a log held in memory (`name` stands for the file in messages); `bytes` must outlive the
  // reader and every view's owner. For tests and the fuzz targets.
  LogReader(std::span<const uint8_t> bytes, std::string name);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;
  // False at the end of the log.
  bool next(LogEvent& event);
  // Same without copying: channel and data point into the mapped file (kMapped) or a chunk
  // (kStreamed) and stay valid while `owner` is held (kMapped: also while the reader lives). For
  // replaying large logs (camera frames) fast.
  struct EventView {
    int64_t utime = 0;
    std::string_view channel;
    std::span<const uint8_t> data;
    std::shared_ptr<const void> owner;
  };
  bool next(EventView& event);
  // kStreamed: the events of `channel` whose data exceeds `read_first` bytes are handed out with only
  // their first `read_first` bytes of data read (a camera frame's header); the view spans the whole
  // data, and read_rest(owner) reads the rest when it is wanted. A replay reads the pixels of the
  // frames a cycle takes, not of every frame (docs/performance.md, "### Replay"). kMapped: nothing
  // to defer, every byte is there.
  void defer(std::string channel, std::size_t read_first);
  // Reads the data a deferred event's view (`owner`, the view's owner) still lacks; does nothing for
  // any other owner, or one read already. Throws std::runtime_error as next() does.
  void read_rest(const std::shared_ptr<const void>& owner);
  // Reads only what `wanted` (the first bytes of a deferred event's view, e.g. the rows of a frame
  // that a crop uses) lacks; read_rest(owner) reads the rest later. An end outside the view means
  // the whole view.
  void read_rest(const std::shared_ptr<const void>& owner, std::span<const uint8_t> wanted);
  // Fraction of the file read, 0..1 (for progress bars).
  double progress() const;
  struct Damage {
    std::string first_problem;    // "FILE: corrupt LCM log: … at byte N", empty if none
    std::size_t skipped_bytes = 0;
    int damaged_places = 0;
    bool truncated_tail = false;  // the log ends inside an event
    int64_t wild_times = 0;       // events whose time was out of line with both neighbours, replaced
    bool damaged() const { return damaged_places > 0 || wild_times > 0; }
    std::string summary() const;  // one line for the user; empty if undamaged
  };
  const Damage& damage() const { return damage_; }

  class Source;  // where the bytes come from (log_reader.cpp)

 private:
  std::string path_;
  std::unique_ptr<Source> source_;
  std::string deferred_channel_;  // empty: nothing deferred
  std::size_t read_first_ = 0;
  std::size_t pos_ = 0;
  int64_t last_utime_ = 0;
  bool have_last_utime_ = false;
  Damage damage_;
};

}  // namespace whiskeye
