// Whisking pattern generator (see pattern.h).
#include <whiskeye/rcp/pattern.h>

#include <cmath>

namespace whiskeye::rcp {

PatternGenerator::PatternGenerator(const PatternParams& params) : params_(params) {}

namespace {
double frac(double x) { return x - std::floor(x); }
}  // namespace

double PatternGenerator::excursion(double phase) const {
  const double u = frac(phase);
  const double p = params_.protraction_fraction;
  if (params_.waveform == Waveform::Sine) {
    // Half a cosine up over the protraction, half a cosine down over the retraction: the WhiskEye
    // sine when p = 0.5, smooth (C1) at both turning points for any p.
    if (u < p) return 0.5 - 0.5 * std::cos(kPi * u / p);
    return 0.5 + 0.5 * std::cos(kPi * (u - p) / (1.0 - p));
  }
  if (u < p) return u / p;
  return 1.0 - (u - p) / (1.0 - p);
}

bool PatternGenerator::protracting(double phase) const { return frac(phase) < params_.protraction_fraction; }

double PatternGenerator::theta(double phase) const {
  return params_.theta_min + excursion(phase) * (params_.theta_max - params_.theta_min);
}

double PatternGenerator::row_phase(double phase, int row) const { return phase + params_.row_phase[row]; }

}  // namespace whiskeye::rcp
