// Fuzz target: slamd's edge, the way a message reaches the core live or in a replay: decoding
// (WHISK_CYCLE's size check first, CAMERA as a view), validation, and the cycle synchroniser, then
// the cycles it hands out through the core with the default configuration.
// Input: records of [1 byte channel: 0 WHISK_CYCLE, 1 CAMERA, 2 ODOMETRY (mod 3)][2 bytes length,
// big-endian][that many bytes of an encoded LCM message] (the last record takes what is left).
// Seeds: fuzz/corpus/slamd_edge, simulator messages shortened by fuzz_make_seeds.
#include "whiskeye/slamd/slam_node.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/robot_geometry.h"

#include <cstdlib>

using namespace whiskeye;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const char* const kChannels[3] = {"WHISK_CYCLE", "CAMERA", "ODOMETRY"};
  static const slam::SlamParams params;
  static const RobotGeometry robot = default_robot_geometry();
  MemoryBus in, out;
  DecodeErrors errors;
  slamd::SlamNode node(in, out, std::make_unique<slam::VitaSlam>(params, robot), slamd::NodeParams{}, errors);
  node.set_logger([](const std::string& line) {
    if (line.empty()) std::abort();
  });
  size_t at = 0;
  while (at + 3 <= size) {
    const char* channel = kChannels[data[at] % 3];
    const size_t len = std::min<size_t>((size_t{data[at + 1]} << 8) | data[at + 2], size - at - 3);
    at += 3;
    // Alternately with and without an owner of the bytes, as a replay and a live bus deliver them.
    if (len % 2 == 0) {
      in.publish_shared(channel, std::span<const uint8_t>(data + at, len), std::make_shared<int>(0));
    } else {
      in.publish_raw(channel, std::span<const uint8_t>(data + at, len));
    }
    at += len;
  }
  node.flush();
  const slam_status_t st = node.status(1);
  if (st.decode_errors != errors.total()) std::abort();
  return 0;
}
