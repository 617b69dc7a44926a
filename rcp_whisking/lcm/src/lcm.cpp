// rcp's types as LCM messages (see lcm.h).
#include "whiskeye/rcp/lcm.h"

#include <cstddef>

namespace whiskeye::rcp {

void to_lcm(const WhiskCycle& in, whisk_cycle_t& out) {
  out.cycle = in.cycle;
  out.utime_start = in.utime_start;
  out.utime_end = in.utime_end;
  out.utime = in.utime_end;
  out.num_whiskers = kNumWhiskers;
  out.num_samples = static_cast<int32_t>(in.samples.size());
  out.num_missing = in.num_missing;
  out.sample_utime.resize(in.samples.size());
  out.sample_valid.resize(in.samples.size());
  out.phase.resize(in.samples.size());
  out.theta.assign(in.samples.size(), std::vector<float>(kNumWhiskers));
  out.deflection_x.assign(in.samples.size(), std::vector<float>(kNumWhiskers));
  out.deflection_y.assign(in.samples.size(), std::vector<float>(kNumWhiskers));
  out.contact.assign(in.samples.size(), std::vector<int8_t>(kNumWhiskers));
  for (std::size_t i = 0; i < in.samples.size(); ++i) {
    const WhiskCycle::Sample& s = in.samples[i];
    out.sample_utime[i] = s.utime;
    out.sample_valid[i] = s.valid ? 1 : 0;
    out.phase[i] = static_cast<int8_t>(s.phase);
    for (int w = 0; w < kNumWhiskers; ++w) {
      out.theta[i][w] = s.theta[w];
      out.deflection_x[i][w] = s.deflection_x[w];
      out.deflection_y[i][w] = s.deflection_y[w];
      out.contact[i][w] = s.contact[w] ? 1 : 0;
    }
  }
}

whisk_cycle_t to_lcm(const WhiskCycle& in) {
  whisk_cycle_t out;
  to_lcm(in, out);
  return out;
}

rcp_state_t to_lcm(const ControlOutput& in) {
  rcp_state_t out;
  fill_rcp_state(in.utime, in.cycle, static_cast<int8_t>(in.phase), in.cycle_phase, in.enabled, in.contact,
                 in.theta_ceiling, in.theta_command, out);
  return out;
}

}  // namespace whiskeye::rcp
