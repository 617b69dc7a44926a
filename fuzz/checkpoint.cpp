// Fuzz target: the checkpoint loader, both halves: the file's header (parse_checkpoint: magic,
// version, size, checksum) and the state inside it (VitaSlam::deserialise). The harness recomputes
// the checksums, so the fuzzer does not stop at them and reaches the parsers.
// Input: byte 0 selects: even = the bytes are a whole checkpoint file (its CRC field is made to
// match); odd = the bytes are VitaSlam's unsealed state, sealed and wrapped in a header here, with
// byte 0's bits 1-2 choosing the mode the loader expects (visual, tactile, vita).
// Seeds: fuzz/corpus/checkpoint, states of a short simulator run (fuzz_make_seeds).
#include "whiskeye/slamd/checkpoint_store.h"

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/vita_slam.h"

#include <vector>

using namespace whiskeye;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const RobotGeometry robot = default_robot_geometry();
  const uint8_t selector = data[0];
  std::vector<uint8_t> file;
  if ((selector & 1) == 0) {
    file.assign(data + 1, data + size);
    if (file.size() >= slamd::kCheckpointHeaderSize) {
      // The CRC this header (the fuzzer's magic, version, sequence and size) should hold for this
      // payload: every file the fuzzer makes passes the checksum and reaches the checks after it.
      const std::span<const uint8_t> header(file.data(), slamd::kCheckpointHeaderSize);
      const uint32_t crc = slamd::checkpoint_crc(header, std::span<const uint8_t>(file).subspan(slamd::kCheckpointHeaderSize));
      for (int i = 0; i < 4; ++i) file[12 + static_cast<size_t>(i)] = static_cast<uint8_t>(crc >> (8 * i));
    }
  } else {
    std::vector<uint8_t> state(data + 1, data + size);
    slam::VitaSlam::seal(state);
    file = slamd::checkpoint_header(1, state);
    file.insert(file.end(), state.begin(), state.end());
  }
  slamd::Checkpoint cp;
  try {
    cp = slamd::parse_checkpoint(file, "fuzz.vslam");
  } catch (const slamd::CheckpointError&) {
    return 0;
  }
  slam::SlamParams params;
  static const slam::Mode kModes[4] = {slam::Mode::Visual, slam::Mode::Tactile, slam::Mode::Vita, slam::Mode::Vita};
  params.mode = kModes[(selector >> 1) & 3];
  try {
    slam::VitaSlam s = slam::VitaSlam::deserialise(cp.payload, params, robot);
    // A state that loads must serialise again (what the next checkpoint does).
    (void)s.serialise();
  } catch (const std::exception&) {
  }
  return 0;
}
