// The pure parts of the whisker bring-up are sealed: whiskerd's control core, the calibration
// estimators, the simulated bring-up sessions and the candump format bring in no LCM and no YAML
// parser. Checked at compile time: this file includes their public headers and fails to compile if
// one of them pulled in LCM's generated types or yaml-cpp.
#include "whiskeye/calibrate/estimators.h"
#include "whiskeye/calibrate/recording.h"
#include "whiskeye/can/candump.h"
#include "whiskeye/sim/bringup.h"
#include "whiskeye/whiskerd/whiskerd_core.h"

#include <gtest/gtest.h>

#ifdef _LCM_LIB_INLINE_H
#error "a pure header includes LCM: whiskerd's LCM conversion lives in whiskeye/whiskerd/lcm.h"
#endif
#ifdef YAML_CPP_API
#error "a pure header includes yaml-cpp: keep it behind ParamNode (common/params.h)"
#endif

TEST(SealedBringup, PureHeadersCompileWithoutLcmOrYaml) { SUCCEED(); }
