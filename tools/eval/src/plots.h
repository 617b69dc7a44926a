// PNG plots of one evaluated run (the paper's Fig. 4 and 5): the aligned experience map over the
// ground truth, and the re-localisations coloured correct / incorrect.
#pragma once

#include "whiskeye/eval/metrics.h"

#include <string>

namespace whiskeye::eval {

// Writes `path`; throws std::runtime_error if it cannot.
void plot_experience_map(const std::string& path, const std::string& title, const EvalInput& input,
                         const EvalResult& result);
void plot_relocalisations(const std::string& path, const std::string& title, const EvalInput& input,
                          const EvalResult& result, const EvalParams& params);

}  // namespace whiskeye::eval
