// A raw SocketCAN socket: RAII, classic and FD frames, id filters, receive with a timeout, kernel
// receive timestamps, error frames. It knows nothing of whiskers (the protocol lives in
// whisker_protocol.h). No POSIX types in the interface.
//
// Bus health: the kernel reports controller state changes as error frames; the socket turns them into
// a BusState and counts them. Bus-off is recovered by the driver (ip link ... restart-ms) or by
// restarting the interface; the socket itself survives an interface going down and coming back
// (reopen()), so the process never has to restart.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace whiskeye::can {

struct Frame {
  uint32_t id = 0;
  bool extended = false;  // 29-bit id
  bool rtr = false;       // remote transmission request (classic only: a DLC, no data)
  bool fd = false;        // CAN FD frame (up to 64 bytes)
  bool brs = false;       // FD bit-rate switch
  uint8_t len = 0;
  std::array<uint8_t, 64> data{};
  int64_t rx_utime = 0;  // kernel receive timestamp, microseconds since the epoch (received frames)

  std::span<const uint8_t> payload() const { return {data.data(), len}; }
};

// Matches data frames with an 11-bit id: extended and remote (RTR) frames never pass a filter, so
// a CANopen tool's RTR or a 29-bit id whose low bits look like a sample cannot be taken for one.
struct Filter {
  uint32_t id = 0;
  uint32_t mask = 0x7ff;  // bits of the 11-bit id that must match
};

enum class BusState { kErrorActive, kErrorWarning, kErrorPassive, kBusOff };
const char* bus_state_name(BusState s);

// What an error frame says, as a pure function of its id and payload (linux/can/error.h).
struct ErrorInfo {
  bool bus_off = false;
  bool restarted = false;  // controller back to error-active after bus-off
  bool passive = false;    // rx or tx error-passive
  bool warning = false;    // rx or tx error-warning
  bool back_to_active = false;
  bool other = false;      // protocol, ack, transceiver, lost arbitration, ...
};
ErrorInfo classify_error_frame(uint32_t can_id, std::span<const uint8_t> data);
// Next bus state after an error frame.
BusState next_bus_state(BusState current, const ErrorInfo& e);

struct Counters {
  int64_t rx_frames = 0;
  int64_t tx_frames = 0;
  int64_t tx_errors = 0;     // send failed (buffer full, interface down)
  int64_t error_frames = 0;  // error frames received from the kernel
  int64_t bus_off = 0;       // transitions to bus-off
  int64_t error_passive = 0; // transitions to error-passive
  int64_t reopens = 0;
  int64_t rx_overflow = 0;   // frames the kernel dropped because the receive queue was full
};

class Socket {
 public:
  // Opens and binds a raw CAN socket on `interface`. It receives classic and FD frames alike, so that
  // a frame of the type the bus is not configured for reaches its reader (and is counted there)
  // where the kernel would drop it unseen, and sends either. Throws std::runtime_error naming the
  // interface and the cause.
  explicit Socket(const std::string& interface);
  ~Socket();
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;

  // Only frames matching one of the filters are received (error frames always are). Empty = all.
  void set_filters(const std::vector<Filter>& filters);
  // Kernel receive queue size, so a stalled reader loses no frames for a while (privileged processes
  // may exceed net.core.rmem_max). Kept across reopen(). Returns the size granted.
  int set_receive_buffer(int bytes);

  enum class Rx { kFrame, kTimeout, kErrorFrame, kDown };
  // Waits up to timeout_us for a frame. kErrorFrame updates state(); kDown: the interface went away
  // (call reopen()).
  Rx receive(Frame& frame, int64_t timeout_us);
  // False if the frame could not be queued (counted); never blocks.
  bool send(const Frame& frame);
  // Closes and reopens on the same interface with the same filters; false (and closed) on failure.
  bool reopen();

  BusState state() const { return state_; }
  const Counters& counters() const { return counters_; }
  const std::string& interface() const { return interface_; }
  bool is_open() const { return fd_ >= 0; }
  // A reason string for the last failure (for logs). Kept in a fixed buffer: a failing send or
  // receive (every period during bus-off) records it without allocating on a real-time thread.
  const char* last_error() const { return last_error_.data(); }

 private:
  void open_socket();
  void close_socket();
  void apply_filters();
  // Formats the reason into last_error_: "CAN <interface>: <what>[: <strerror(err)>]".
  void set_error(const char* what, int err);

  std::string interface_;
  int fd_ = -1;
  std::vector<Filter> filters_;
  int rcvbuf_ = 0;
  uint32_t last_drop_count_ = 0;
  // The kernel reports an interface going down once, as a pending socket error, and whichever call
  // comes next takes it: a receive (poll error, kDown) or a send (ENETDOWN). So a send that fails
  // with ENETDOWN or ENODEV after one that succeeded is that report, and the next receive returns
  // kDown. Failing sends on a socket opened while the interface is down are not (no reopen loop).
  bool sent_ok_ = false;
  bool down_reported_by_send_ = false;
  BusState state_ = BusState::kErrorActive;
  Counters counters_;
  std::array<char, 160> last_error_{};
};

}  // namespace whiskeye::can
