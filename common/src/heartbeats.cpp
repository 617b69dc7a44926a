// Worker liveness for the watchdog keep-alive; see heartbeats.h.
#include "whiskeye/common/heartbeats.h"

#include <cstdio>
#include <stdexcept>

namespace whiskeye {

int WorkerHeartbeats::add(std::string name, int64_t limit_us, int64_t now_us) {
  if (limit_us <= 0) throw std::invalid_argument("heartbeat limit of the " + name + " thread must be positive");
  auto w = std::make_unique<Worker>();
  w->name = std::move(name);
  w->limit_us = limit_us;
  w->last_us.store(now_us, std::memory_order_relaxed);
  workers_.push_back(std::move(w));
  return static_cast<int>(workers_.size()) - 1;
}

void WorkerHeartbeats::beat(int index, int64_t now_us) {
  workers_.at(static_cast<size_t>(index))->last_us.store(now_us, std::memory_order_relaxed);
}

std::string WorkerHeartbeats::stalled(int64_t now_us) const {
  for (const auto& w : workers_) {
    const int64_t silent = now_us - w->last_us.load(std::memory_order_relaxed);
    if (silent > w->limit_us) {
      char text[160];
      std::snprintf(text, sizeof text, "%s thread silent for %.2f s (limit %.2f s)", w->name.c_str(),
                    static_cast<double>(silent) * 1e-6, static_cast<double>(w->limit_us) * 1e-6);
      return text;
    }
  }
  return {};
}

}  // namespace whiskeye
