// whiskerd's two threads and what they share:
//   ControlLoop (the control thread: SCHED_FIFO + mlockall when permitted) runs at the sample rate
//   on absolute clock_nanosleep deadlines: drain CAN frames -> WhiskerCore::step -> motor command on
//   the bus (wp::encode_command) -> the period's messages to the publisher through a lock-free ring.
//   Log lines travel the same way, so the control thread never blocks on stderr.
//   publish_loop (the publisher thread) is the only one that touches LCM, so a slow or failing LCM
//   never delays the control loop; it also reopens a CAN socket that went down (socket_custody.h)
//   and pets the watchdog while the control loop makes progress.
#pragma once

#include "whiskeye/common/bus.h"
#include "whiskeye/common/latency_stats.h"
#include "whiskeye/common/log.h"
#include "whiskeye/common/service.h"
#include "whiskeye/common/socket_custody.h"
#include "whiskeye/common/spsc_ring.h"
#include "whiskeye/can/can_socket.h"
#include "whiskeye/whiskerd/config.h"
#include "whiskeye/whiskerd/whiskerd_core.h"

#include <time.h>

#include <array>
#include <atomic>
#include <memory>
#include <string>

namespace whiskeye::whiskerd {

// One item handed from the control thread to the publisher thread.
struct Item {
  enum class Kind { kNone, kPeriod, kStatus, kLog } kind = Kind::kNone;
  PeriodOutput period;
  StatusSnapshot status;
  std::array<char, 192> text{};
  LogLevel level = LogLevel::kInfo;  // of a kLog item (common/log.h)
};
using Ring = SpscRing<Item, 256>;

struct Shared {
  Ring ring;
  // Published whisk cycles travel back to the control thread, which recycles their storage: the
  // real-time loop then never allocates at a cycle completion. A full ring frees the cycle here.
  SpscRing<std::unique_ptr<rcp::WhiskCycle>, 8> used_cycles;
  // A CAN socket that went down is reopened by the publisher thread, not in the control loop.
  SocketCustody<can::Socket> can_socket;
  std::atomic<int64_t> rt_periods{0};
  std::atomic<bool> rt_done{false};
  std::atomic<int> exit_code{0};
};

// The control thread's state. Construct it on the control thread: the constructor asks for real-time
// scheduling and locked memory for the calling thread before the core allocates anything.
class ControlLoop {
 public:
  // `stop` becomes true when the daemon is asked to stop (a signal): the core retracts, then run() ends.
  ControlLoop(const Params& p, std::unique_ptr<can::Socket> sock, gpio::MotorLines& lines, Shared& shared,
              ServiceNotifier& service, const std::atomic<bool>& stop);
  ControlLoop(const ControlLoop&) = delete;
  ControlLoop& operator=(const ControlLoop&) = delete;

  // Runs the periods until the core has finished or something threw. Whatever happened, the enable
  // line ends low and the boards get a last disabled command; a failure sets shared.exit_code to 1.
  // Sets shared.rt_done at the end.
  void run();

 private:
  void period();
  void receive_frames();
  void push_status(int64_t done);
  void send_command(const wp::MotorCommand& cmd);
  // Drops the enable line and sends the boards a disabled command. Never throws: a second failure
  // while shutting down must not end in std::terminate with the line high. Returns "" or why the
  // line could not be dropped (the boards' disabled command went out regardless).
  std::string disable_motors();
  // printf-style log line: formatted into a fixed buffer, no allocation; a full ring loses it. The
  // publisher thread writes it at `level` (common/log.h).
  void log(LogLevel level, const char* fmt, ...) __attribute__((format(printf, 3, 4)));

  const Params& p_;
  const bool rt_;  // first: real-time scheduling before anything below allocates
  std::unique_ptr<can::Socket> sock_;
  gpio::MotorLines& lines_;
  Shared& shared_;
  ServiceNotifier& service_;
  const std::atomic<bool>& stop_;
  WhiskerCore core_;
  const int64_t period_ns_;
  const int64_t period_us_;
  const int per_status_;
  const int64_t status_period_us_;
  int64_t next_status_mono_;
  LatencyStats wake_, loop_, jitter_;
  Item item_;
  Item log_item_;  // reused to avoid a 6 kB stack object per log line
  LineGuard guard_;
  int64_t last_wake_ = 0;
  can::Frame frame_;
  can::BusState bus_state_;
  can::Counters can_counters_;  // as of the last period the socket was here
  std::unique_ptr<rcp::WhiskCycle> used_cycle_;
  wp::CommandFrames command_frames_;
  timespec next_{};
};

// The publisher thread: until the control loop is done and the ring empty.
void publish_loop(const Params& p, Bus& bus, Shared& shared, ServiceNotifier& service);

}  // namespace whiskeye::whiskerd
