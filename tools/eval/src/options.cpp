// Parsing of vita-eval's compound option values (options.h).
#include "whiskeye/eval/options.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace whiskeye::eval {

namespace {

std::string g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

std::string parse_false_closure_tolerance(const std::string& text, EvalParams& params) {
  const std::string option = "--false-closure-tolerance";
  std::istringstream in(text);
  double m = 0.0, deg = 0.0;
  char comma = 0;
  if (!(in >> m >> comma >> deg) || comma != ',' || !(in >> std::ws).eof()) {
    return option + " must be M,DEG (metres, degrees), got '" + text + "'";
  }
  if (!std::isfinite(m) || !std::isfinite(deg) || m <= 0.0 || deg <= 0.0 || deg > 180.0) {
    return option + ": M must be a positive distance and DEG in (0, 180], got '" + text + "'";
  }
  if (m < params.correct_position_m || deg_to_rad(deg) < params.correct_angle_rad) {
    return option + " " + text + " is narrower than the correct-relocalisation thresholds (" +
           g(params.correct_position_m) + " m, " + g(rad_to_deg(params.correct_angle_rad)) +
           " deg): a re-localisation would be both correct and false";
  }
  params.false_closure_position_m = m;
  params.false_closure_angle_rad = deg_to_rad(deg);
  return "";
}

}  // namespace whiskeye::eval
