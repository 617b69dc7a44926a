// The simulator's outputs as the real drivers publish them: converts SimSink calls into the LCM
// messages (WHISKER_SAMPLE, RCP_STATE, WHISK_CYCLE, ODOMETRY, CAMERA) plus the simulator-only
// GROUND_TRUTH, SIM_CONTACT_TRUTH and SIM_FAULT, and publishes them on a Bus stamped with the sample utime
// (for a LogWriterBus: the log event time). Not part of the pure library (it knows LCM).
#pragma once

#include "whiskeye/common/bus.h"
#include "whiskeye/rcp/lcm.h"
#include "whiskeye/sim/simulator.h"

#include <whiskeye/image_t.hpp>
#include <whiskeye/sim_fault_t.hpp>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace whiskeye::sim {

// Nominal raw scales of the simulated sensors (documented in docs/simulator.md):
constexpr double kRawHallPerUnit = 2000.0;    // raw_x/raw_y = round(deflection · 2000)
constexpr double kRawThetaPerRad = 10000.0;   // raw_theta = round(θ · 10000), 0.1 mrad counts

// WHISKER_SAMPLE with raw counts at the nominal scales and status as whiskerd sets it: STALE for a
// stale whisker, FAULT for a faulty one (or any other invalid one), SATURATED at the plant's clip.
// RCP_STATE and WHISK_CYCLE go out as whiskerd's do, through rcp::to_lcm (whiskeye/rcp/lcm.h).
whisker_sample_t to_lcm(const rcp::WhiskerSample& s, const WhiskerHealth& health, double saturation);
sim_fault_t to_lcm(const FaultEvent& e);

class LcmSink : public SimSink {
 public:
  // `set_time` stamps the following publications (LogWriterBus::set_time; may be empty). CAMERA
  // frames go out in `camera.format` (MJPEG: JPEG-encoded at `camera.jpeg_quality`).
  LcmSink(Bus& bus, std::function<void(int64_t)> set_time, const CameraNoise& camera, double saturation);

  void whisker_sample(const rcp::WhiskerSample& sample, const WhiskerHealth& health) override;
  void rcp_state(const rcp::ControlOutput& out) override;
  void whisk_cycle(const rcp::WhiskCycle& cycle) override;
  void contact_truth(const ContactTruth& truth) override;
  void odometry(int64_t utime, int64_t seq, const OdometrySample& odom) override;
  void ground_truth(int64_t utime, const Pose2& T_world_base) override;
  void camera(int64_t utime, int64_t seq, const std::vector<uint8_t>& grey, int width, int height) override;
  void fault(const FaultEvent& event) override;

  // Messages published per channel.
  const std::map<std::string, int64_t>& counts() const { return counts_; }

 private:
  template <typename T>
  void put(const std::string& channel, int64_t utime, const T& msg);

  Bus& bus_;
  std::function<void(int64_t)> set_time_;
  CameraFormat format_;
  int jpeg_quality_;
  double saturation_;
  std::map<std::string, int64_t> counts_;
  image_t image_;
  // MJPEG: libturbojpeg's compressor (a tjhandle, kept out of this header), its output buffer and
  // the constant chroma planes.
  std::unique_ptr<void, int (*)(void*)> jpeg_{nullptr, nullptr};
  std::vector<unsigned char> jpeg_buffer_;
  std::vector<unsigned char> neutral_chroma_;
};

}  // namespace whiskeye::sim
