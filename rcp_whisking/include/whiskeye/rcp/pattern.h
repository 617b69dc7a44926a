// Whisking pattern generator: the nominal protraction target of every whisker as a function of time
// since whisking started. Pure: time is an argument. A cycle starts at theta_min (start of
// protraction); with the default sine and protraction_fraction 0.5 this is the WhiskEye pattern
// theta = theta_min + (0.5 + 0.5 sin(2 pi f t')) (theta_max - theta_min) shifted to start at the trough.
#pragma once

#include <whiskeye/rcp/params.h>

namespace whiskeye::rcp {

class PatternGenerator {
 public:
  explicit PatternGenerator(const PatternParams& params);

  // Position 0..1 between theta_min and theta_max at cycle phase `phase` (cycles, any real value;
  // only the fractional part matters).
  double excursion(double phase) const;
  // Protracting at this cycle phase? (fractional part < protraction_fraction)
  bool protracting(double phase) const;
  // Nominal target theta at this cycle phase, rad.
  double theta(double phase) const;
  // Cycle phase of `row` when the master phase is `phase` (adds the row's phase lead).
  double row_phase(double phase, int row) const;

  const PatternParams& params() const { return params_; }

 private:
  PatternParams params_;
};

}  // namespace whiskeye::rcp
