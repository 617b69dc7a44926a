// The motor safety lines of the whisker head: one output (motor enable) and inputs (driver fault,
// emergency stop). whiskerd talks to this interface; GpiodMotorLines drives real lines with libgpiod
// (C++ bindings; tested against the kernel's gpio-mockup in the VM, vm.gpio), FakeMotorLines lets unit
// tests script faults, and NoMotorLines is for rigs without lines (--no-gpio).
#pragma once

#include <memory>
#include <string>

namespace whiskeye::gpio {

class MotorLines {
 public:
  virtual ~MotorLines() = default;
  virtual void set_enable(bool on) = 0;
  // True if a fault or emergency stop is active now or an edge into it happened since the last
  // call (an edge is never missed even if the line bounced back). Never blocks.
  virtual bool fault_active() = 0;
  virtual std::string describe() const = 0;
};

struct LineNames {
  std::string enable = "WHISKER_MOTOR_EN";    // output, high = motors powered
  std::string fault = "WHISKER_MOTOR_FAULT";  // input, active low (driver open-drain)
  std::string estop = "WHISKER_ESTOP";        // input, active low; "" = not wired
  bool fault_active_low = true;
  bool estop_active_low = true;
};

// Finds the lines by name on any gpiochip. Throws std::runtime_error naming a missing line.
std::unique_ptr<MotorLines> open_gpiod_lines(const LineNames& names, const std::string& consumer);

class NoMotorLines : public MotorLines {
 public:
  void set_enable(bool) override {}
  bool fault_active() override { return false; }
  std::string describe() const override { return "no GPIO lines (--no-gpio)"; }
};

// Scriptable lines for tests.
class FakeMotorLines : public MotorLines {
 public:
  void set_enable(bool on) override {
    enable = on;
    ++enable_writes;
  }
  bool fault_active() override {
    const bool f = fault || fault_edge;
    fault_edge = false;
    return f;
  }
  std::string describe() const override { return "fake lines"; }
  bool enable = false;
  int enable_writes = 0;
  bool fault = false;
  bool fault_edge = false;
};

}  // namespace whiskeye::gpio
