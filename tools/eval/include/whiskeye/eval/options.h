// vita-eval's option values that need more than CLI11's checks, parsed where a unit test reaches them.
#pragma once

#include "whiskeye/eval/metrics.h"

#include <string>

namespace whiskeye::eval {

// `--false-closure-tolerance M,DEG`: sets params.false_closure_position_m and
// params.false_closure_angle_rad. Returns "" on success, else the one-line reason (without the
// program's name) and leaves `params` as it was. A tolerance below the paper's correct thresholds
// already in `params` is refused: a re-localisation would then be both correct and false.
std::string parse_false_closure_tolerance(const std::string& text, EvalParams& params);

}  // namespace whiskeye::eval
