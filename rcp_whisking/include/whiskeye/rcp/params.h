// Parameters of the whisking controller (pattern generator, contact detector, RCP law) with the
// defaults documented in docs/rcp-whisking.md and config/rcp.yaml. Struct fields are SI (rad, s);
// YAML keys that are not SI say so (_deg, _hz).
#pragma once

#include <whiskeye/common/params.h>
#include <whiskeye/common/se2.h>
#include <whiskeye/rcp/types.h>

#include <array>
#include <string>

namespace whiskeye::rcp {

enum class Waveform { Sine, Triangle };
// Whiskeye: ceiling = theta_max + m (theta_rcp - theta_max), m = running max of the contact level in
// the cycle (the WhiskEye law). RateLimited: on contact the ceiling starts at the command and
// withdraws at rate_limit * contact level. Off: pattern only (the "without RCP" comparison).
enum class RcpLaw { Whiskeye, RateLimited, Off };

const char* to_string(Waveform w);
const char* to_string(RcpLaw law);

struct PatternParams {
  double frequency_hz = 1.0;                       // whisk cycles per second (the paper: 1 Hz)
  double theta_min = -30.0 * kPi / 180.0;  // start of protraction, rad
  double theta_max = 45.0 * kPi / 180.0;   // end of protraction, rad
  double theta_rest = -30.0 * kPi / 180.0; // command when not whisking, rad
  double theta_limit = 60.0 * kPi / 180.0; // |command| never exceeds this (joint range), rad
  Waveform waveform = Waveform::Sine;
  double protraction_fraction = 0.5;               // part of the cycle spent protracting (0.5 = WhiskEye sine)
  std::array<double, kWhiskerRows> row_phase{};        // per-row phase lead, in cycles (0..1)
  double ramp_time = 0.5;                          // s, amplitude ramp on enable / disable
  double max_rate = 15.0;                          // rad/s, slew limit on the command (never steps)
};

struct DetectorParams {
  int learn_cycles = 2;             // free whisking cycles used to learn the noise floor
  int learn_min_samples = 200;      // per whisker, else the default threshold stays
  int learn_guard_samples = 25;     // samples after a contact ends that are not learned from (50 ms)
  double default_threshold = 0.08;  // |xy| threshold until the floor is learned
  double threshold_min = 0.04;      // learned threshold never below this (WhiskEye's 0.04)
  double threshold_max = 0.3;       // learned threshold never above this
  // Learned threshold = noise_factor x the noise_quantile of |xy| during free whisking. A quantile
  // (not mean + k sigma) so that the contacts made while learning, which sit in the upper tail,
  // cannot inflate it as long as they fill less than 1 - noise_quantile of the learning samples.
  double noise_quantile = 0.75;
  double noise_factor = 4.0;        // Rayleigh noise of sigma s: 4 x 1.665 s = 6.7 s, P(exceed) ~ 2e-10
  double release_ratio = 0.6;       // hysteresis: contact ends below release_ratio * threshold
  double contact_gain = 5.0;        // contact level c = clip(gain (|xy| - threshold), 0, 1)
};

struct RcpParams {
  RcpLaw law = RcpLaw::Whiskeye;
  double theta_rcp = -60.0 * kPi / 180.0;  // ceiling at full contact level, rad
  // On contact onset during protraction, cap the ceiling at the command of the previous period, so
  // protraction stops in the very step that detects the contact, even while c is still small.
  bool freeze_on_contact = true;
  double rate_limit = 4.0;  // rad/s at c = 1, RateLimited law only
};

struct ControllerParams {
  PatternParams pattern;
  DetectorParams detector;
  RcpParams rcp;
};

// Loads sections `pattern`, `detector`, `rcp` of `node` (absent keys keep their defaults) and
// validates them; a wrong type, out-of-range value or inconsistent pair is a ParamError naming the
// key. It does NOT call check_no_unknown_keys(): the caller does, after loading every section of its
// file (the rcp keys may live inside a larger robot file).
void load(const ParamNode& node, ControllerParams& params);

// Cross-field checks (theta_min < theta_max, ...) for parameters built in code; throws ParamError.
void validate(const ControllerParams& params);

}  // namespace whiskeye::rcp
