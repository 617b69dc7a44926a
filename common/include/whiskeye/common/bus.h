// The message transport seam. Node code talks to a Bus; the same code then runs
//   - on the robot over LCM (LcmBus, udpm://),
//   - on a recorded log (LogReader feeding handlers, LogWriterBus collecting output),
//   - in a unit test (MemoryBus, synchronous, in-process).
// Typed helpers encode/decode LCM types (message_layout.h); a message that fails to decode is
// counted and reported to DecodeErrors, never thrown at the node.
#pragma once

#include "whiskeye/common/message_layout.h"  // encode_message, decode_message

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace lcm {
class LCM;
class LogFile;
}  // namespace lcm

namespace whiskeye {

struct MessageInfo {
  std::string channel;
  int64_t recv_utime = 0;  // when the transport received it (log event time on a log)
  // Set when the bytes outlive the handler call: holding it keeps `data` valid (e.g. a replayed
  // log's mapping), so a handler may keep a view instead of a copy. Null: copy what you keep.
  std::shared_ptr<const void> data_owner;
};

class Bus {
 public:
  using RawHandler = std::function<void(std::span<const uint8_t> data, const MessageInfo& info)>;

  virtual ~Bus() = default;
  virtual void publish_raw(const std::string& channel, std::span<const uint8_t> data) = 0;
  // `channel` is a POSIX extended regex matched against the whole channel name, as in LCM.
  virtual void subscribe_raw(const std::string& channel, RawHandler handler) = 0;
  // Messages a transport could not send and dropped (see LcmBus); daemons report it in their status.
  virtual int64_t publish_errors() const { return 0; }
};

// Counts messages that failed to decode, per channel; optionally tells a callback (to log).
class DecodeErrors {
 public:
  using Callback = std::function<void(const std::string& channel, const std::string& reason)>;
  void set_callback(Callback cb);
  void record(const std::string& channel, const std::string& reason);
  int64_t total() const { return total_.load(); }
  int64_t count(const std::string& channel) const;

 private:
  std::atomic<int64_t> total_{0};
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> per_channel_;
  Callback callback_;
};

template <typename T>
void publish(Bus& bus, const std::string& channel, const T& msg) {
  const std::vector<uint8_t> buf = encode_message(msg);
  bus.publish_raw(channel, buf);
}

// Subscribes with decoding. handler is void(const T&) or void(const T&, const MessageInfo&).
template <typename T, typename Handler>
void subscribe(Bus& bus, const std::string& channel, Handler handler, DecodeErrors& errors) {
  bus.subscribe_raw(channel, [handler = std::move(handler), &errors](std::span<const uint8_t> data,
                                                                     const MessageInfo& info) {
    T msg;
    std::string reason;
    if (!decode_message(data, msg, &reason)) {
      errors.record(info.channel, reason);
      return;
    }
    if constexpr (std::is_invocable_v<Handler, const T&, const MessageInfo&>) {
      handler(msg, info);
    } else {
      handler(msg);
    }
  });
}

// In-process bus: publish delivers synchronously to every matching subscription. For tests.
class MemoryBus : public Bus {
 public:
  void publish_raw(const std::string& channel, std::span<const uint8_t> data) override;
  // Same, telling handlers that `data` stays valid while `data_owner` is held (MessageInfo).
  void publish_shared(const std::string& channel, std::span<const uint8_t> data,
                      std::shared_ptr<const void> data_owner);
  void subscribe_raw(const std::string& channel, RawHandler handler) override;
  // Time stamped on delivered messages (recv_utime).
  void set_time(int64_t utime) { now_utime_ = utime; }

 private:
  struct Sub;
  std::vector<std::shared_ptr<Sub>> subs_;
  int64_t now_utime_ = 0;
};

// True when `channel` is a plain name, not a regex (so exact comparison gives the same answer).
bool is_plain_channel_name(const std::string& channel);

// Datagrams the kernel dropped on this process's UDP sockets because their receive buffer was full
// (the `drops` column of /proc/self/net/udp and udp6, for the sockets among /proc/self/fd), or -1 if
// that cannot be read. LCM itself counts nothing it drops (lcm 1.3.1 has no statistics; a message
// missing fragments is dropped silently): this is the part of its losses the kernel can tell.
int64_t udp_receive_drops();
// The same from the text of /proc/net/udp, for the sockets whose inode is in `inodes`.
int64_t udp_receive_drops(std::string_view proc_net_udp, const std::vector<uint64_t>& inodes);

// LCM over a URL ("" = $LCM_DEFAULT_URL or LCM's default). Throws std::runtime_error if LCM cannot
// start (e.g. no multicast route for udpm://).
class LcmBus : public Bus {
 public:
  explicit LcmBus(const std::string& url = "");
  ~LcmBus() override;
  LcmBus(const LcmBus&) = delete;
  LcmBus& operator=(const LcmBus&) = delete;

  // A message that cannot be sent (ENOBUFS with the socket's buffer full, ENETUNREACH or ENETDOWN
  // with the interface down) is lost, as a datagram lost on the wire would be: it is counted in
  // publish_errors(), logged to stderr at the 1st, 10th, 100th, ... failure, and never thrown, so a
  // network hiccup cannot end a daemon (or its real-time publisher thread). Thread-safe.
  void publish_raw(const std::string& channel, std::span<const uint8_t> data) override;
  void subscribe_raw(const std::string& channel, RawHandler handler) override;
  int64_t publish_errors() const override { return publish_errors_.load(); }
  // LCM's receive thread holds each message for the subscriptions it matches until handle_timeout()
  // hands it over; a subscription already holding its capacity of unhandled messages loses every
  // further one without a trace (no counter, no log line, not even with LCM_DBG). LCM's default
  // capacity, 30, is overrun by any burst the loop does not drain as fast as it arrives: a sender
  // catching up after a pause, a busy cycle, a replay at speed. Sets the capacity (messages) of this
  // bus's subscriptions to `channel` (as given to subscribe_raw), those made and those to come;
  // 0: no limit (memory then grows for as long as the loop is behind).
  void set_queue_capacity(const std::string& channel, int messages);
  // Dispatches at most one message; 0 on timeout, >0 if handled, <0 on error.
  int handle_timeout(int timeout_ms);
  int fileno();

 private:
  struct Adapter;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Adapter>> adapters_;
  std::map<std::string, int> queue_capacity_;  // by channel, for subscriptions made later
  std::atomic<int64_t> publish_errors_{0};
};

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

  class Source;  // where the bytes come from (bus.cpp)

 private:
  std::string path_;
  std::unique_ptr<Source> source_;
  std::size_t pos_ = 0;
  int64_t last_utime_ = 0;
  bool have_last_utime_ = false;
  Damage damage_;
};

// A Bus that appends every published message to an LCM log file, stamped with set_time().
// Subscriptions are delivered synchronously (like MemoryBus) so a node can also read its own output.
class LogWriterBus : public Bus {
 public:
  explicit LogWriterBus(const std::string& path);  // throws std::runtime_error naming the file
  ~LogWriterBus() override;
  LogWriterBus(const LogWriterBus&) = delete;
  LogWriterBus& operator=(const LogWriterBus&) = delete;

  void publish_raw(const std::string& channel, std::span<const uint8_t> data) override;
  void subscribe_raw(const std::string& channel, RawHandler handler) override;
  void set_time(int64_t utime);
  int64_t events_written() const { return events_; }

 private:
  std::unique_ptr<lcm::LogFile> log_;
  MemoryBus local_;
  int64_t now_utime_ = 0;
  int64_t events_ = 0;
};

}  // namespace whiskeye
