// whiskerd's outputs as LCM messages (daemon side): a period's WHISKER_SAMPLE and RCP_STATE, and
// DRIVER_STATUS. A completed cycle goes out through rcp::to_lcm (whiskeye/rcp/lcm.h), as vita-sim's do.
// The control core (whiskerd_core.h) never sees an LCM type.
#pragma once

#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/rcp/lcm.h>

#include "whiskeye/whiskerd/whiskerd_core.h"

namespace whiskeye::whiskerd {

void to_lcm(const PeriodOutput& in, whisker_sample_t& sample, rcp_state_t& state);
void to_lcm(const StatusSnapshot& in, driver_status_t& out);

}  // namespace whiskeye::whiskerd
