// The pure libraries are sealed: their public headers bring in no YAML parser (params.h keeps
// yaml-cpp inside common/src/params.cpp), no LCM and no image codec. Checked where it matters, at
// compile time: this file includes every public header of whiskeye_common's pure part, of the SLAM
// core, of rcp_whisking and of whisker_protocol, and fails to compile if one of them pulled in
// yaml-cpp (which defines YAML_CPP_API in every public header), LCM's generated types or OpenCV's
// imgcodecs. (docs/architecture.md, "The sealed core".)
#include <whiskeye/common/big_endian.h>
#include <whiskeye/common/channels.h>
#include <whiskeye/common/jpeg_markers.h>
#include <whiskeye/common/latency_stats.h>
#include <whiskeye/common/log_throttle.h>
#include <whiskeye/common/odometry_limits.h>
#include <whiskeye/common/params.h>
#include <whiskeye/common/robot_geometry.h>
#include <whiskeye/common/se2.h>
#include <whiskeye/common/sequence_gaps.h>
#include <whiskeye/common/spsc_ring.h>
#include <whiskeye/common/utime.h>
#include <whiskeye/common/whisker_array.h>
#include <whiskeye/rcp/contact_detector.h>
#include <whiskeye/rcp/controller.h>
#include <whiskeye/rcp/cycle_assembler.h>
#include <whiskeye/rcp/experiment.h>
#include <whiskeye/rcp/params.h>
#include <whiskeye/rcp/pattern.h>
#include <whiskeye/rcp/plant.h>
#include <whiskeye/rcp/rcp.h>
#include <whiskeye/rcp/types.h>
#include <whiskeye/slam/experience_map.h>
#include <whiskeye/slam/localiser.h>
#include <whiskeye/slam/pose_cells.h>
#include <whiskeye/slam/row_store.h>
#include <whiskeye/slam/tactile_template.h>
#include <whiskeye/slam/template_store.h>
#include <whiskeye/slam/types.h>
#include <whiskeye/slam/visual_template.h>
#include <whiskeye/slam/vita_slam.h>
#include <whiskeye/whisker_protocol/whisker_protocol.h>

#include <gtest/gtest.h>

#ifdef YAML_CPP_API
#error "a core header includes yaml-cpp: keep it behind ParamNode (common/params.h)"
#endif
#ifdef _LCM_LIB_INLINE_H
#error "a core header includes LCM"
#endif
#ifdef OPENCV_IMGCODECS_HPP
#error "a core header includes OpenCV's imgcodecs: images are decoded at the daemon's edge"
#endif

TEST(SealedCore, PublicHeadersCompileWithoutYamlLcmOrCodecs) { SUCCEED(); }
