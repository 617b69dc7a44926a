// Reads a slamd output log into the metrics' plain input structs (the only LCM-aware part of vita-eval).
#pragma once

#include "whiskeye/eval/metrics.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace whiskeye::eval {

struct LoadedRun {
  std::string path;
  std::string mode;  // "visual", "tactile", "vita" or "unknown" (from VITA_MAP, else VITA_POSE)
  EvalInput input;
  std::map<std::string, int64_t> decode_errors;  // per channel
  int64_t map_messages = 0;
  std::string log_damage;  // LogReader::Damage::summary(): empty unless the log was damaged
};

// Throws std::runtime_error with a one-line reason if the file cannot be read or has no VITA_MAP
// (not a slamd output log). A log without GROUND_TRUTH (a real robot's run) loads with
// `input.ground_truth` empty. A damaged log (a corrupt event, a cut-off end) is evaluated from the
// events that could be read, and `log_damage` says what was skipped.
LoadedRun load_run(const std::string& path);

// Every GROUND_TRUTH sample of a log (vita-sim's, or a slamd output log that copied them): the truth
// of the session that made a saved map. Throws std::runtime_error with a one-line reason if the file
// cannot be read or has none.
std::vector<PoseSample> load_ground_truth(const std::string& path);

}  // namespace whiskeye::eval
