// SocketCAN raw socket (see can_socket.h).
#include "whiskeye/can/can_socket.h"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace whiskeye::can {

const char* bus_state_name(BusState s) {
  switch (s) {
    case BusState::kErrorActive: return "error-active";
    case BusState::kErrorWarning: return "error-warning";
    case BusState::kErrorPassive: return "error-passive";
    case BusState::kBusOff: return "bus-off";
  }
  return "?";
}

ErrorInfo classify_error_frame(uint32_t can_id, std::span<const uint8_t> d) {
  ErrorInfo e;
  auto byte = [&](std::size_t i) -> uint8_t { return i < d.size() ? d[i] : 0; };
  if (can_id & CAN_ERR_BUSOFF) e.bus_off = true;
  if (can_id & CAN_ERR_RESTARTED) e.restarted = true;
  if (can_id & CAN_ERR_CRTL) {
    const uint8_t c = byte(1);
    if (c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) e.passive = true;
    if (c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) e.warning = true;
#ifdef CAN_ERR_CRTL_ACTIVE
    if (c & CAN_ERR_CRTL_ACTIVE) e.back_to_active = true;
#endif
  }
  if (can_id & (CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB | CAN_ERR_PROT | CAN_ERR_TRX | CAN_ERR_ACK |
                CAN_ERR_BUSERROR)) {
    e.other = true;
  }
  return e;
}

BusState next_bus_state(BusState current, const ErrorInfo& e) {
  if (e.bus_off) return BusState::kBusOff;
  if (e.restarted || e.back_to_active) return BusState::kErrorActive;
  if (e.passive) return BusState::kErrorPassive;
  if (e.warning) return current == BusState::kErrorPassive ? current : BusState::kErrorWarning;
  return current;
}

Socket::Socket(const std::string& interface) : interface_(interface) {
  open_socket();
}

Socket::~Socket() { close_socket(); }

void Socket::close_socket() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void Socket::open_socket() {
  auto fail = [&](const std::string& what) {
    const std::string msg = "CAN " + interface_ + ": " + what + ": " + std::strerror(errno);
    close_socket();
    throw std::runtime_error(msg);
  };
  if (interface_.empty() || interface_.size() >= IFNAMSIZ) {
    throw std::runtime_error("CAN interface name '" + interface_ + "' is invalid");
  }
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC | SOCK_NONBLOCK, CAN_RAW);
  if (fd_ < 0) fail("socket(PF_CAN) (kernel without can-raw?)");
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, interface_.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd_, SIOCGIFINDEX, &ifr) < 0) fail("no such interface");
  // FD frames too on a classic bus: without this the kernel drops them before any reader sees them.
  int fd_on = 1;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &fd_on, sizeof(fd_on)) < 0) fail("enable FD frames");
  can_err_mask_t err_mask = CAN_ERR_MASK;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof(err_mask)) < 0) {
    fail("enable error frames");
  }
  int on = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof(on)) < 0) fail("enable timestamps");
  if (::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof(on)) < 0) fail("enable drop counting");
  last_drop_count_ = 0;
  sent_ok_ = false;
  down_reported_by_send_ = false;
  apply_filters();
  if (rcvbuf_ > 0) set_receive_buffer(rcvbuf_);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) < 0) fail("bind");
  // Bound to an interface that is down, the socket starts with ENETDOWN pending (can-raw's bind
  // reports it). It is not news: it receives once the interface comes up. Taken here, it cannot make
  // the first receive return kDown, which would reopen the socket again and again while the
  // interface stays down.
  int pending = 0;
  socklen_t len = sizeof(pending);
  ::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &pending, &len);
  if (pending != 0) set_error("opened while the interface is down", pending);
}

void Socket::apply_filters() {
  if (fd_ < 0) return;
  std::vector<can_filter> f;
  for (const Filter& x : filters_) f.push_back({x.id & CAN_SFF_MASK, (x.mask & CAN_SFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG});
  if (filters_.empty()) f.push_back({0, 0});  // everything
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, f.data(),
                   static_cast<socklen_t>(f.size() * sizeof(can_filter))) < 0) {
    throw std::runtime_error("CAN " + interface_ + ": set filters: " + std::strerror(errno));
  }
}

int Socket::set_receive_buffer(int bytes) {
  rcvbuf_ = bytes;
  if (fd_ < 0) return 0;
  if (::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof(bytes)) < 0) {
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof(bytes));  // capped at rmem_max
  }
  int granted = 0;
  socklen_t len = sizeof(granted);
  ::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &granted, &len);
  return granted;
}

void Socket::set_filters(const std::vector<Filter>& filters) {
  filters_ = filters;
  apply_filters();
}

void Socket::set_error(const char* what, int err) {
  std::snprintf(last_error_.data(), last_error_.size(), "CAN %s: %s: %s", interface_.c_str(), what, std::strerror(err));
}

bool Socket::reopen() {
  close_socket();
  try {
    open_socket();
  } catch (const std::exception& e) {
    std::snprintf(last_error_.data(), last_error_.size(), "%s", e.what());
    return false;
  }
  ++counters_.reopens;
  state_ = BusState::kErrorActive;
  return true;
}

Socket::Rx Socket::receive(Frame& frame, int64_t timeout_us) {
  if (fd_ < 0 || down_reported_by_send_) return Rx::kDown;  // last_error() says why
  pollfd p{fd_, POLLIN, 0};
  const int timeout_ms = timeout_us <= 0 ? 0 : static_cast<int>((timeout_us + 999) / 1000);
  const int n = ::poll(&p, 1, timeout_ms);
  if (n == 0 || (n < 0 && errno == EINTR)) return Rx::kTimeout;
  if (n < 0 || (p.revents & (POLLERR | POLLHUP | POLLNVAL))) {
    // A pending socket error (e.g. ENETDOWN) is cleared by reading it.
    int err = n < 0 ? errno : 0;
    socklen_t len = sizeof(err);
    if (n >= 0) ::getsockopt(fd_, SOL_SOCKET, SO_ERROR, &err, &len);
    if (err != 0) {
      set_error("socket error", err);
    } else {
      std::snprintf(last_error_.data(), last_error_.size(), "CAN %s: socket error (poll events %d)", interface_.c_str(),
                    static_cast<int>(p.revents));
    }
    if (err == ENETDOWN || err == ENODEV || (p.revents & (POLLHUP | POLLNVAL))) return Rx::kDown;
    return Rx::kTimeout;
  }
  canfd_frame raw{};
  iovec iov{&raw, sizeof(raw)};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(uint32_t))];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof(control);
  const ssize_t got = ::recvmsg(fd_, &msg, 0);
  if (got < 0) {
    if (errno == EAGAIN || errno == EINTR) return Rx::kTimeout;
    set_error("receive", errno);
    return (errno == ENETDOWN || errno == ENODEV) ? Rx::kDown : Rx::kTimeout;
  }
  frame = Frame{};
  frame.fd = got == static_cast<ssize_t>(CANFD_MTU);
  frame.len = raw.len > 64 ? 64 : raw.len;
  if (!frame.fd && frame.len > 8) frame.len = 8;
  std::memcpy(frame.data.data(), raw.data, frame.len);
  frame.extended = raw.can_id & CAN_EFF_FLAG;
  frame.rtr = !frame.fd && (raw.can_id & CAN_RTR_FLAG);
  frame.id = raw.can_id & (frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  frame.brs = frame.fd && (raw.flags & CANFD_BRS);
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
      timeval tv;
      std::memcpy(&tv, CMSG_DATA(c), sizeof(tv));
      frame.rx_utime = static_cast<int64_t>(tv.tv_sec) * 1000000 + tv.tv_usec;
    } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      // The socket's cumulative drop counter: count what was added since the last frame.
      uint32_t drops;
      std::memcpy(&drops, CMSG_DATA(c), sizeof(drops));
      counters_.rx_overflow += static_cast<uint32_t>(drops - last_drop_count_);
      last_drop_count_ = drops;
    }
  }
  if (raw.can_id & CAN_ERR_FLAG) {
    ++counters_.error_frames;
    const BusState before = state_;
    state_ = next_bus_state(state_, classify_error_frame(raw.can_id & CAN_ERR_MASK, frame.payload()));
    if (state_ != before && state_ == BusState::kBusOff) ++counters_.bus_off;
    if (state_ != before && state_ == BusState::kErrorPassive) ++counters_.error_passive;
    frame.id = raw.can_id & CAN_ERR_MASK;
    return Rx::kErrorFrame;
  }
  ++counters_.rx_frames;
  return Rx::kFrame;
}

bool Socket::send(const Frame& frame) {
  if (fd_ < 0) {
    ++counters_.tx_errors;
    return false;
  }
  canfd_frame raw{};
  raw.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0) | (frame.rtr && !frame.fd ? CAN_RTR_FLAG : 0);
  const std::size_t max = frame.fd ? 64 : 8;
  raw.len = frame.len > max ? static_cast<uint8_t>(max) : frame.len;
  std::memcpy(raw.data, frame.data.data(), raw.len);
  if (frame.fd && frame.brs) raw.flags |= CANFD_BRS;
  const std::size_t size = frame.fd ? CANFD_MTU : CAN_MTU;
  const ssize_t n = ::write(fd_, &raw, size);
  if (n != static_cast<ssize_t>(size)) {
    const int err = errno;
    ++counters_.tx_errors;
    set_error("send", err);
    if (err == ENETDOWN || err == ENODEV) {
      down_reported_by_send_ = down_reported_by_send_ || sent_ok_;
      sent_ok_ = false;
    }
    return false;
  }
  sent_ok_ = true;
  ++counters_.tx_frames;
  return true;
}

}  // namespace whiskeye::can
