// Output of vita-eval: the Table-I-like text table and the JSON document.
#pragma once

#include "whiskeye/eval/metrics.h"

#include <nlohmann/json.hpp>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace whiskeye::eval {

struct RunReport {
  std::string label;
  std::string path;
  std::string mode;
  std::size_t pose_samples = 0;
  std::size_t events = 0;
  std::size_t map_experiences = 0;
  std::size_t map_links = 0;
  std::size_t map_links_revoked = 0;
  std::size_t ground_truth_samples = 0;
  std::map<std::string, int64_t> decode_errors;
  std::string log_damage;  // empty: the log was read whole
  std::vector<FaultEvent> faults;  // simulated faults beginning and ending (SIM_FAULT)
  int64_t start_utime = 0;         // run_start_utime(): the origin of the times printed (s)
  EvalResult result;
};

// A row of the paper's Table I, as printed there (metrics.md).
struct PaperRow {
  std::string method;
  double enm;
  double arr;
  double arcr;
  double lem_pos;
  double lem_pos_spread;
  double lem_ori;
  double lem_ori_spread;
};

// "visual", "tactile" or "vita"; nothing for another name.
std::optional<PaperRow> paper_row(const std::string& name);

// `params` names the thresholds in each run's block.
std::string format_table(const std::vector<RunReport>& runs, const EvalParams& params,
                         const std::vector<PaperRow>& paper);

nlohmann::json to_json(const std::vector<RunReport>& runs, const EvalParams& params,
                       const std::vector<PaperRow>& paper);

// Poses in the TUM trajectory format (Sturm et al. 2012), which evo and the TUM benchmark's tools
// read: a line per pose, "timestamp x y z qx qy qz qw", the timestamp in seconds (microseconds
// kept), z = 0, the heading as a rotation about z.
std::string format_tum(const std::vector<PoseSample>& poses);

// The per-cycle trace as CSV with a header row; a field that does not apply is empty (docs/evaluation.md).
std::string format_trace_csv(const std::vector<CycleTrace>& rows);

}  // namespace whiskeye::eval
