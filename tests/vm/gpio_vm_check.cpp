// VM test program for whiskerd's motor lines over libgpiod (GpiodMotorLines) against a real gpiochip:
// the kernel's gpio-mockup driver, loaded by scenario_gpio.sh with three named lines. The lines'
// outside world is gpio-mockup's debugfs folder: reading a line's file gives its value, writing 0/1
// pulls an input there (and raises its edge interrupt). One PASS/FAIL line per behaviour.
//   gpio_vm_check --chip-debugfs DIR --results FILE
#include "whiskeye/gpio/motor_lines.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <thread>

using namespace whiskeye;

namespace {

std::ofstream results;
int failures = 0;

void report(const std::string& name, bool ok, const std::string& why = "") {
  results << (ok ? "PASS " : "FAIL ") << name << (ok ? "" : ": " + why) << std::endl;
  std::cout << (ok ? "PASS " : "FAIL ") << name << (ok ? "" : ": " + why) << std::endl;
  failures += ok ? 0 : 1;
}

struct Mockup {
  std::string dir;
  std::string read(int offset) const {
    std::ifstream f(dir + "/" + std::to_string(offset));
    std::string v;
    f >> v;
    return v;
  }
  void pull(int offset, int value) const {
    std::ofstream f(dir + "/" + std::to_string(offset));
    f << value << std::flush;
    if (!f) throw std::runtime_error("cannot write " + dir + "/" + std::to_string(offset));
  }
};

// Lets the simulated interrupt's work run before the next poll.
void settle() { std::this_thread::sleep_for(std::chrono::milliseconds(20)); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"whiskerd motor lines VM test against gpio-mockup"};
  std::string dir, results_path;
  app.add_option("--chip-debugfs", dir)->required();
  app.add_option("--results", results_path)->required();
  CLI11_PARSE(app, argc, argv);
  results.open(results_path, std::ios::app);
  const Mockup chip{dir};

  gpio::LineNames names;  // the mockup's line names (module parameter gpio_mockup_named_lines)
  names.enable = "gpio-mockup-A-0";
  names.fault = "gpio-mockup-A-1";
  names.estop = "gpio-mockup-A-2";
  // The driver's fault and the e-stop are active low: idle, their pull-ups hold them high.
  chip.pull(1, 1);
  chip.pull(2, 1);

  try {
    gpio::LineNames missing = names;
    missing.fault = "WHISKER_MOTOR_FAULT";
    gpio::open_gpiod_lines(missing, "gpio_vm_check");
    report("a_missing_line_is_an_error_naming_it", false, "opened without the line");
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    report("a_missing_line_is_an_error_naming_it", what.find("WHISKER_MOTOR_FAULT") != std::string::npos, what);
  }

  std::unique_ptr<gpio::MotorLines> lines;
  try {
    lines = gpio::open_gpiod_lines(names, "gpio_vm_check");
    report("the_lines_are_found_by_name_and_requested", true);
  } catch (const std::exception& e) {
    report("the_lines_are_found_by_name_and_requested", false, e.what());
    return 1;
  }
  report("the_enable_output_starts_low", chip.read(0) == "0", "enable reads " + chip.read(0));
  lines->set_enable(true);
  const std::string on = chip.read(0);
  lines->set_enable(false);
  const std::string off = chip.read(0);
  report("set_enable_drives_the_output", on == "1" && off == "0", "on: " + on + ", off: " + off);

  settle();
  report("idle_inputs_are_no_fault", !lines->fault_active() && !lines->fault_active());

  // A held fault: active while held, then one more report for the edges, then quiet.
  chip.pull(1, 0);
  settle();
  const bool held1 = lines->fault_active(), held2 = lines->fault_active();
  chip.pull(1, 1);
  settle();
  const bool released_edge = lines->fault_active(), quiet = !lines->fault_active();
  report("a_held_fault_is_active_while_held", held1 && held2);
  report("a_released_fault_reports_its_edge_once_then_clears", released_edge && quiet);

  // A pulse shorter than a poll period: gone by the next poll, still seen through its edges.
  chip.pull(1, 0);
  chip.pull(1, 1);
  settle();
  const bool pulse = lines->fault_active(), after_pulse = !lines->fault_active();
  report("a_fault_pulse_between_two_polls_is_not_missed", pulse && after_pulse,
         std::string("first poll ") + (pulse ? "fault" : "no fault") + ", second " + (after_pulse ? "clear" : "fault"));

  chip.pull(2, 0);
  chip.pull(2, 1);
  settle();
  const bool estop = lines->fault_active(), after_estop = !lines->fault_active();
  report("an_emergency_stop_pulse_is_a_fault", estop && after_estop);

  lines->set_enable(true);
  lines.reset();
  report("releasing_the_lines_drives_enable_low", chip.read(0) == "0", "enable reads " + chip.read(0));
  return failures == 0 ? 0 : 1;
}
