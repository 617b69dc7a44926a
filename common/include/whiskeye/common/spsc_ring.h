// A bounded single-producer single-consumer ring: the real-time control thread hands messages to the
// publisher thread without locks, allocation or blocking. A full ring drops the new item (counted by
// the caller) rather than wait: the control loop must never stall on LCM.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <utility>

namespace whiskeye {

template <typename T, std::size_t N>
class SpscRing {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "capacity must be a power of two");

 public:
  // Producer only. False if full (item untouched).
  bool try_push(T& item) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) == N) return false;
    slots_[head & (N - 1)] = std::move(item);
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  // Consumer only. False if empty.
  bool try_pop(T& out) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (head_.load(std::memory_order_acquire) == tail) return false;
    out = std::move(slots_[tail & (N - 1)]);
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }
  std::size_t size() const { return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire); }
  static constexpr std::size_t capacity() { return N; }

 private:
  std::array<T, N> slots_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace whiskeye
