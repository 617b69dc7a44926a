// The VM checker programs' verdicts: one "PASS name" / "FAIL name: why" line per behaviour, appended
// to the scenario's results file (which run-vm reads back on the host) and echoed to stdout.
#pragma once

#include <fstream>
#include <iostream>
#include <string>
#include <utility>

namespace whiskeye::vm {

class Report {
 public:
  // `prefix` goes before every name (one checker run twice in a scenario, e.g. "classic_").
  explicit Report(const std::string& results_path, std::string prefix = "")
      : out_(results_path, std::ios::app), prefix_(std::move(prefix)) {}

  void operator()(const std::string& name, bool ok, const std::string& why = "") {
    const std::string line = (ok ? "PASS " : "FAIL ") + prefix_ + name + (ok ? "" : ": " + why);
    out_ << line << std::endl;
    std::cout << line << std::endl;
    failures_ += !ok;
  }
  // The checker's exit status: 0 only if every behaviour passed.
  int exit_code() const { return failures_ == 0 ? 0 : 1; }

 private:
  std::ofstream out_;
  std::string prefix_;
  int failures_ = 0;
};

}  // namespace whiskeye::vm
