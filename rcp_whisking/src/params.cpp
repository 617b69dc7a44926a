// Loading and validating the whisking controller's parameters (see params.h for the defaults).
#include <whiskeye/rcp/params.h>

#include <cmath>

namespace whiskeye::rcp {

const char* to_string(Phase phase) {
  switch (phase) {
    case Phase::Protract: return "protract";
    case Phase::Retract: return "retract";
    case Phase::Rest: return "rest";
  }
  return "?";
}

const char* to_string(Waveform w) { return w == Waveform::Sine ? "sine" : "triangle"; }

const char* to_string(RcpLaw law) {
  switch (law) {
    case RcpLaw::Whiskeye: return "whiskeye";
    case RcpLaw::RateLimited: return "rate_limited";
    case RcpLaw::Off: return "off";
  }
  return "?";
}

namespace {

// Angles are written in degrees in YAML (readable), held in rad.
void get_deg(const ParamNode& node, const std::string& key, double& rad, double min_deg, double max_deg) {
  double deg = rad_to_deg(rad);
  node.get(key, deg, min_deg, max_deg);
  rad = deg_to_rad(deg);
}

[[noreturn]] void fail(const ParamNode& node, const std::string& key, const std::string& what) {
  throw ParamError(node.source() + ": '" + node.path_of(key) + "' " + what);
}

}  // namespace

void load(const ParamNode& node, ControllerParams& params) {
  const ParamNode pat = node.section("pattern");
  PatternParams& p = params.pattern;
  pat.get("frequency_hz", p.frequency_hz, 0.05, 20.0);
  get_deg(pat, "theta_min_deg", p.theta_min, -90.0, 90.0);
  get_deg(pat, "theta_max_deg", p.theta_max, -90.0, 90.0);
  get_deg(pat, "theta_rest_deg", p.theta_rest, -90.0, 90.0);
  get_deg(pat, "theta_limit_deg", p.theta_limit, 1.0, 90.0);
  std::string waveform = to_string(p.waveform);
  pat.get("waveform", waveform);
  if (waveform == "sine") {
    p.waveform = Waveform::Sine;
  } else if (waveform == "triangle") {
    p.waveform = Waveform::Triangle;
  } else {
    fail(pat, "waveform", "= \"" + waveform + "\" must be sine or triangle");
  }
  pat.get("protraction_fraction", p.protraction_fraction, 0.1, 0.9);
  std::vector<double> row_phase(p.row_phase.begin(), p.row_phase.end());
  pat.get("row_phase", row_phase);
  if (row_phase.size() != p.row_phase.size()) {
    fail(pat, "row_phase", "must list " + std::to_string(kWhiskerRows) + " values (one per row), got " +
                               std::to_string(row_phase.size()));
  }
  for (std::size_t i = 0; i < row_phase.size(); ++i) {
    if (!(row_phase[i] >= 0.0 && row_phase[i] < 1.0)) {
      // A char, not a one-character string: GCC 12 at -O3 raises a bogus -Wrestrict on "x" + std::string&&
      // (GCC bug 105329), which breaks the Release build.
      fail(pat, "row_phase", '[' + std::to_string(i) + "] must be in [0, 1) cycles");
    }
    p.row_phase[i] = row_phase[i];
  }
  pat.get("ramp_time", p.ramp_time, 0.0, 10.0);
  pat.get("max_rate", p.max_rate, 0.1, 1000.0);

  const ParamNode det = node.section("detector");
  DetectorParams& d = params.detector;
  det.get("learn_cycles", d.learn_cycles, 0, 1000);
  det.get("learn_min_samples", d.learn_min_samples, 1, 1000000);
  det.get("learn_guard_samples", d.learn_guard_samples, 0, 100000);
  det.get("default_threshold", d.default_threshold, 1e-4, 1.0);
  det.get("threshold_min", d.threshold_min, 1e-4, 1.0);
  det.get("threshold_max", d.threshold_max, 1e-4, 1.0);
  det.get("noise_quantile", d.noise_quantile, 0.05, 0.99);
  det.get("noise_factor", d.noise_factor, 1.0, 100.0);
  det.get("release_ratio", d.release_ratio, 0.05, 1.0);
  det.get("contact_gain", d.contact_gain, 0.01, 1000.0);

  const ParamNode rcp = node.section("rcp");
  RcpParams& r = params.rcp;
  std::string law = to_string(r.law);
  rcp.get("law", law);
  if (law == "whiskeye") {
    r.law = RcpLaw::Whiskeye;
  } else if (law == "rate_limited") {
    r.law = RcpLaw::RateLimited;
  } else if (law == "off") {
    r.law = RcpLaw::Off;
  } else {
    fail(rcp, "law", "= \"" + law + "\" must be whiskeye, rate_limited or off");
  }
  get_deg(rcp, "theta_rcp_deg", r.theta_rcp, -90.0, 90.0);
  rcp.get("freeze_on_contact", r.freeze_on_contact);
  rcp.get("rate_limit", r.rate_limit, 0.01, 1000.0);

  try {
    validate(params);
  } catch (const ParamError& e) {
    throw ParamError(node.source() + ": " + e.what());
  }
}

void validate(const ControllerParams& params) {
  const PatternParams& p = params.pattern;
  const auto bad = [](const std::string& what) { throw ParamError(what); };
  if (!(p.frequency_hz > 0.0 && std::isfinite(p.frequency_hz))) bad("'pattern.frequency_hz' must be > 0");
  if (!(p.theta_min < p.theta_max)) bad("'pattern.theta_max_deg' must be greater than 'pattern.theta_min_deg'");
  if (!(p.theta_limit > 0.0)) bad("'pattern.theta_limit_deg' must be > 0");
  if (std::abs(p.theta_min) > p.theta_limit || std::abs(p.theta_max) > p.theta_limit) {
    bad("'pattern.theta_min_deg' and 'pattern.theta_max_deg' must lie within +-'pattern.theta_limit_deg'");
  }
  if (std::abs(p.theta_rest) > p.theta_limit) bad("'pattern.theta_rest_deg' must lie within +-'pattern.theta_limit_deg'");
  if (!(p.protraction_fraction > 0.0 && p.protraction_fraction < 1.0)) bad("'pattern.protraction_fraction' must be in (0, 1)");
  if (!(p.ramp_time >= 0.0)) bad("'pattern.ramp_time' must be >= 0");
  if (!(p.max_rate > 0.0)) bad("'pattern.max_rate' must be > 0");
  const DetectorParams& d = params.detector;
  if (!(d.threshold_min <= d.threshold_max)) bad("'detector.threshold_min' must not exceed 'detector.threshold_max'");
  if (!(d.release_ratio > 0.0 && d.release_ratio <= 1.0)) bad("'detector.release_ratio' must be in (0, 1]");
  if (!(d.default_threshold > 0.0)) bad("'detector.default_threshold' must be > 0");
  if (d.learn_cycles < 0) bad("'detector.learn_cycles' must be >= 0");
  const RcpParams& r = params.rcp;
  if (!(r.theta_rcp < p.theta_max)) bad("'rcp.theta_rcp_deg' must be below 'pattern.theta_max_deg'");
  if (std::abs(r.theta_rcp) > p.theta_limit) bad("'rcp.theta_rcp_deg' must lie within +-'pattern.theta_limit_deg'");
  if (!(r.rate_limit > 0.0)) bad("'rcp.rate_limit' must be > 0");
}

}  // namespace whiskeye::rcp
