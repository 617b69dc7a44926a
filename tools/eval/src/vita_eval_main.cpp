// vita-eval: the paper's Table I metrics (LEM, ExM, EnM; ../shared/design/metrics.md), and the false
// closures beside ARCR, from one or more slamd output logs. Prints the table, optionally writes JSON,
// plots (PNG and SVG, optionally over a vita-sim world) and per-cycle traces. A log without
// GROUND_TRUTH (a real robot's run) is drawn and counted; what needs truth is reported as unavailable.
// Wiring only: the options and the run are in vita_eval_app.h.
#include "vita_eval_app.h"

#include "whiskeye/common/cli.h"

int main(int argc, char** argv) {
  whiskeye::cli::Program program("vita-eval",
                                 "vita-eval: LEM, ExM (ARR, ARCR, valid fraction) and EnM of slamd output logs against "
                                 "their GROUND_TRUTH, as in the paper's Table I, and plots of any run, with or without "
                                 "ground truth (see docs/evaluation.md)");
  whiskeye::eval::VitaEvalOptions options;
  whiskeye::eval::add_vita_eval_options(program.app(), options);
  return program.run(argc, argv, [&] { return whiskeye::eval::run_vita_eval(options); });
}
