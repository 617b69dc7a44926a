// The CAN socket is reopened off the real-time thread.
//
// Reopening makes slow calls that may allocate: socket(), ioctl, setsockopt with the filter
// vector, bind, and on failure an exception with a formatted message (every retry while a USB
// adapter is unplugged). None of that belongs in the control loop. So the socket changes hands
// through two lock-free rings:
//   - the control thread gives a dead socket up (give_up) and runs on without CAN;
//   - the reopening thread (whiskerd's publisher) tries to reopen it, first at once and then with
//     a backoff from 100 ms doubling to 5 s (service); a socket that goes down again within 5 s of
//     its reopen keeps its backoff, so an interface that flaps, or a socket that reports itself
//     down at once, costs one reopen per backoff and not one per control period;
//   - the control thread takes it back at the start of a period (take_back).
// While the socket is away no samples arrive, so the core's staleness checks stop the motors as
// they would for a silent bus, and no commands are sent.
//
// Templated on the socket (anything with `bool reopen()`) so that the hand-over is tested with a
// scripted socket and two real threads; whiskerd uses can::Socket.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>

#include "whiskeye/common/spsc_ring.h"

namespace whiskeye {

template <typename Socket>
class SocketCustody {
 public:
  static constexpr int64_t kFirstBackoffUs = 100000;
  static constexpr int64_t kMaxBackoffUs = 5000000;

  enum class Attempt { kNone, kReopened, kFailed };

  // Control thread: hands a socket that went down over to be reopened; `sock` is empty afterwards.
  // Never blocks. There is one socket, so the ring always has room for it.
  void give_up(std::unique_ptr<Socket>& sock) { to_reopen_.try_push(sock); }

  // Control thread: true (and `sock` set) when the reopened socket is back.
  bool take_back(std::unique_ptr<Socket>& sock) { return reopened_.try_pop(sock); }

  // Reopening thread, called often (every millisecond or so): takes a socket given up, and when its
  // backoff has passed tries once to reopen it; a reopened socket goes back to the control thread.
  Attempt service(int64_t now_us) {
    if (!held_ && to_reopen_.try_pop(held_)) {
      if (!last_reopen_us_ || now_us - *last_reopen_us_ >= kMaxBackoffUs) {
        next_attempt_us_ = now_us;  // it had been up a while: a new outage
        backoff_us_ = kFirstBackoffUs;
      } else {
        next_attempt_us_ = *last_reopen_us_ + backoff_us_;  // down again soon after its reopen
        grow_backoff();
      }
    }
    if (!held_ || now_us < next_attempt_us_) return Attempt::kNone;
    if (held_->reopen()) {
      last_reopen_us_ = now_us;
      reopened_.try_push(held_);
      return Attempt::kReopened;
    }
    next_attempt_us_ = now_us + backoff_us_;
    grow_backoff();
    return Attempt::kFailed;
  }

  // Reopening thread: the socket it is trying to reopen (for its last error), or null.
  const Socket* held() const { return held_.get(); }
  // Reopening thread: when the next attempt is due (monotonic microseconds), if a socket is held.
  int64_t next_attempt_us() const { return next_attempt_us_; }

 private:
  SpscRing<std::unique_ptr<Socket>, 2> to_reopen_;  // control thread -> reopening thread
  SpscRing<std::unique_ptr<Socket>, 2> reopened_;   // reopening thread -> control thread
  std::unique_ptr<Socket> held_;                    // reopening thread only
  void grow_backoff() { backoff_us_ = std::min(backoff_us_ * 2, kMaxBackoffUs); }

  std::optional<int64_t> last_reopen_us_;
  int64_t next_attempt_us_ = 0;
  int64_t backoff_us_ = kFirstBackoffUs;
};

}  // namespace whiskeye
