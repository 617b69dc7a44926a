// The message transport seam. Node code talks to a Bus; the same code then runs
//   - on the robot over LCM (LcmBus, udpm://),
//   - on a recorded log (LogReader feeding handlers, LogWriterBus collecting output),
//   - in a unit test (MemoryBus, synchronous, in-process).
// Typed helpers encode/decode LCM types (message_layout.h); a message that fails to decode is
// counted and reported to DecodeErrors, never thrown at the node.
#pragma once

#include "whiskeye/common/log_reader.h"      // LogReader: the log side of the seam
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
