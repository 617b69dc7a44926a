// The wire format of the whisking controller's data: rcp's plain types as the LCM messages
// WHISKER_SAMPLE, RCP_STATE and WHISK_CYCLE (docs/lcm-channels.md). One home for the conversions
// that whiskerd (from the real boards) and vita-sim (from the simulated plant) both publish, so the
// two cannot drift apart. Library whiskeye_rcp_lcm: the pure whiskeye_rcp knows no LCM.
//
// The functions live in namespace rcp next to the types they convert, so a call to_lcm(cycle, msg)
// finds them by argument-dependent lookup from any namespace.
#pragma once

#include "whiskeye/rcp/controller.h"
#include "whiskeye/rcp/types.h"

#include <whiskeye/rcp_state_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>
#include <whiskeye/whisker_sample_t.hpp>

#include <cstdint>

namespace whiskeye::rcp {

// WHISK_CYCLE: one assembled whisk cycle, every sample of every whisker; utime = utime_end.
void to_lcm(const WhiskCycle& in, whisk_cycle_t& out);
whisk_cycle_t to_lcm(const WhiskCycle& in);

// RCP_STATE of one control period from its per-whisker values (arrays of float or double, sent as
// float). whiskerd gives the period's epoch time and its enable state (the controller's and the
// safety state machine's); to_lcm(ControlOutput) takes both from the controller (vita-sim).
template <typename Values>
void fill_rcp_state(int64_t utime, int64_t cycle, int8_t phase, double cycle_phase, bool enabled,
                    const Values& contact, const Values& theta_ceiling, const Values& theta_command,
                    rcp_state_t& out) {
  out.utime = utime;
  out.cycle = cycle;
  out.phase = phase;
  out.cycle_phase = cycle_phase;
  out.enabled = enabled;
  out.num_whiskers = kNumWhiskers;
  out.contact.assign(contact.begin(), contact.end());
  out.theta_ceiling.assign(theta_ceiling.begin(), theta_ceiling.end());
  out.theta_command.assign(theta_command.begin(), theta_command.end());
}
rcp_state_t to_lcm(const ControlOutput& in);

// WHISKER_SAMPLE of one period: calibrated θ and deflections (arrays of float or double, sent as
// float), the raw sensor counts and the per-whisker status flags (whisker_sample_t::STATUS_*), which
// whiskerd reads from the boards and vita-sim derives from its plant.
template <typename Values>
void fill_whisker_sample(int64_t utime, int64_t seq, const Values& theta, const Values& deflection_x,
                         const Values& deflection_y, const PerWhisker<int16_t>& raw_x,
                         const PerWhisker<int16_t>& raw_y, const PerWhisker<int16_t>& raw_theta,
                         const PerWhisker<int8_t>& status, whisker_sample_t& out) {
  out.utime = utime;
  out.seq = seq;
  out.num_whiskers = kNumWhiskers;
  out.theta.assign(theta.begin(), theta.end());
  out.deflection_x.assign(deflection_x.begin(), deflection_x.end());
  out.deflection_y.assign(deflection_y.begin(), deflection_y.end());
  out.raw_x.assign(raw_x.begin(), raw_x.end());
  out.raw_y.assign(raw_y.begin(), raw_y.end());
  out.raw_theta.assign(raw_theta.begin(), raw_theta.end());
  out.status.assign(status.begin(), status.end());
}

}  // namespace whiskeye::rcp
