// MotorLines over libgpiod 1.6 (C++ bindings): named lines, the enable output requested low, the
// fault / e-stop inputs requested with edge events so a short pulse between two polls is not lost.
#include <gpiod.hpp>

#include <chrono>
#include <stdexcept>

#include "whiskeye/gpio/motor_lines.h"

namespace whiskeye::gpio {
namespace {

gpiod::line find(const std::string& name) {
  gpiod::line line = gpiod::find_line(name);
  if (!line) throw std::runtime_error("GPIO line '" + name + "' not found on any gpiochip");
  return line;
}

class GpiodMotorLines : public MotorLines {
 public:
  GpiodMotorLines(const LineNames& names, const std::string& consumer) : names_(names) {
    enable_ = find(names.enable);
    enable_.request({consumer, gpiod::line_request::DIRECTION_OUTPUT, 0}, 0);
    fault_ = find(names.fault);
    fault_.request({consumer, gpiod::line_request::EVENT_BOTH_EDGES,
                    names.fault_active_low ? gpiod::line_request::FLAG_ACTIVE_LOW : std::bitset<32>()});
    if (!names.estop.empty()) {
      estop_ = find(names.estop);
      estop_.request({consumer, gpiod::line_request::EVENT_BOTH_EDGES,
                      names.estop_active_low ? gpiod::line_request::FLAG_ACTIVE_LOW : std::bitset<32>()});
    }
  }
  ~GpiodMotorLines() override {
    try {
      enable_.set_value(0);
    } catch (...) {
    }
  }

  void set_enable(bool on) override { enable_.set_value(on ? 1 : 0); }

  bool fault_active() override {
    bool edge = drain(fault_);
    bool active = fault_.get_value() != 0;
    if (estop_) {
      edge = drain(estop_) || edge;
      active = active || estop_.get_value() != 0;
    }
    return active || edge;
  }

  std::string describe() const override {
    return "gpiod lines enable=" + names_.enable + " fault=" + names_.fault +
           (names_.estop.empty() ? "" : " estop=" + names_.estop);
  }

 private:
  // True if any edge was queued. Any edge counts as a fault: a pulse shorter than the poll period
  // shows only as edges, and whiskerd latches faults anyway (re-arming is a restart).
  static bool drain(const gpiod::line& line) {
    bool edge = false;
    while (line.event_wait(std::chrono::nanoseconds(0))) {
      line.event_read();
      edge = true;
    }
    return edge;
  }

  LineNames names_;
  gpiod::line enable_, fault_, estop_;
};

}  // namespace

std::unique_ptr<MotorLines> open_gpiod_lines(const LineNames& names, const std::string& consumer) {
  try {
    return std::make_unique<GpiodMotorLines>(names, consumer);
  } catch (const std::system_error& e) {
    throw std::runtime_error(std::string("GPIO: ") + e.what());
  }
}

}  // namespace whiskeye::gpio
