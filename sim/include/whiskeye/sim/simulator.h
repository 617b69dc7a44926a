// The closed-loop WhiskEye simulation: the robot follows the world's trajectory; every 500 Hz
// control period the whisker/world geometry gives each whisker its obstacle (first-touch angle and
// radial distance), the rcp_whisking plant produces θ and deflections, and the real RCP controller
// commands the next period (closed loop); odometry and ground truth come at 50 Hz and camera frames
// at the robot's frame rate. The world's sensor faults change what the sensors report (as the drivers
// would report it) and are announced as they begin and end. Outputs go to a SimSink as plain
// structs, in time order; vita-sim turns them into LCM messages. Pure: time is the simulated utime,
// randomness is seeded, no I/O.
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/common/whisker_array.h"
#include "whiskeye/sim/odometry.h"
#include "whiskeye/sim/renderer.h"
#include "whiskeye/sim/whisker_contact.h"
#include "whiskeye/sim/world.h"

#include <whiskeye/rcp/controller.h>
#include <whiskeye/rcp/plant.h>

#include <array>
#include <cstdint>
#include <future>
#include <map>
#include <optional>
#include <vector>

namespace whiskeye::sim {

struct SimParams {
  int64_t start_utime = 1'700'000'000'000'000;  // fixed default: runs are reproducible
  double duration = 0.0;          // s; 0 = world.trajectory.laps laps
  uint64_t seed = 1;
  int64_t period_us = kControlPeriodUs;  // control period
  int odometry_divider = 10;      // ODOMETRY and GROUND_TRUTH every 10 periods (50 Hz)
  int contact_update_divider = 5; // obstacles recomputed every 5 periods (the head moves < 1 mm)
  SweepParams sweep;
  // Render the next camera frame on a worker thread while the control loop runs (the trajectory is
  // known ahead, frames are rendered strictly in order, so the output is identical either way).
  bool render_ahead = true;
};

// The true contacts of one whisk cycle: one point per contact onset, head frame at onset time.
struct ContactTruth {
  int64_t utime = 0;  // end of the cycle
  int64_t cycle = 0;
  struct Point {
    int whisker = 0;
    int64_t utime = 0;
    Vec3 p_in_head;
    int solid = -1;  // index of the touched solid (-1: a wall or landmark panel)
  };
  std::vector<Point> points;
};

// Why a whisker's reading is not valid this period. whiskerd tells the cases apart in
// WHISKER_SAMPLE.status and valid = false alone cannot, so the sink gets them beside the sample.
struct WhiskerHealth {
  rcp::PerWhisker<bool> stale{};  // its board sent nothing this period: the last value is repeated
  rcp::PerWhisker<bool> fault{};  // the sensor failed: no deflection, reading invalid
};

// The injected faults (World::faults). Values match sim_fault_t.KIND_*.
enum class FaultKind : int8_t {
  DeadWhisker = 1,
  BoardOffline = 2,
  CameraBlackout = 3,
  CameraFreeze = 4,
  OdometrySlip = 5,
  Kidnap = 6
};

// The world file's key of a fault kind ("dead_whiskers", "board_offline", ...).
const char* to_string(FaultKind kind);

// A fault beginning or ending: ground truth for attributing what an evaluation sees.
struct FaultEvent {
  int64_t utime = 0;  // the first control period in (active) or after (!active) the fault
  FaultKind kind = FaultKind::DeadWhisker;
  bool active = true;
  int index = -1;      // whisker (DeadWhisker) or board (BoardOffline), else -1
  double value = 0.0;  // OdometrySlip: the scale, else 0
  Pose2 pose;          // Kidnap: the true base pose the robot was put down at (its only event, active)
};

// One configured fault over the run, for a summary.
struct FaultRecord {
  FaultKind kind = FaultKind::DeadWhisker;
  int index = -1;
  double value = 0.0;    // OdometrySlip: the scale; Kidnap: the polar angle put down at (rad)
  Pose2 pose;            // Kidnap: the true base pose put down at, once it happened
  int64_t start_us = 0;  // since the start; active in [start_us, end_us)
  int64_t end_us = 0;    // INT64_MAX: the whole run
  int64_t began_utime = -1;  // -1: not (yet) begun / ended
  int64_t ended_utime = -1;
  // What it touched: whisker samples (DeadWhisker: the whisker's; BoardOffline: the board's, one
  // per period), camera frames withheld or repeated, odometry samples scaled.
  int64_t affected = 0;
};

// Receives the simulation's outputs. Calls come in non-decreasing time order.
class SimSink {
 public:
  virtual ~SimSink() = default;
  virtual void whisker_sample(const rcp::WhiskerSample& sample, const WhiskerHealth& health) = 0;
  virtual void rcp_state(const rcp::ControlOutput& out) = 0;
  virtual void whisk_cycle(const rcp::WhiskCycle& cycle) = 0;
  virtual void contact_truth(const ContactTruth& truth) = 0;
  virtual void odometry(int64_t utime, int64_t seq, const OdometrySample& odom) = 0;
  virtual void ground_truth(int64_t utime, const Pose2& T_world_base) = 0;
  // 8-bit grey, row-major.
  virtual void camera(int64_t utime, int64_t seq, const std::vector<uint8_t>& grey, int width, int height) = 0;
  // Before the whisker sample of the period it names.
  virtual void fault(const FaultEvent& event) = 0;
};

// Plant parameters consistent with the robot geometry: lengths from it, and the deflection gain that
// the per-obstacle stiffness scale maps onto each whisker's bend_gain (see Simulator).
rcp::PlantParams plant_params_for(const RobotGeometry& robot, rcp::PlantParams base = {});

class Simulator {
 public:
  Simulator(const World& world, const RobotGeometry& robot, const rcp::ControllerParams& controller,
            const rcp::PlantParams& plant, const SimParams& params);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  int64_t total_steps() const { return total_steps_; }
  int64_t steps_done() const { return step_; }
  double duration() const;  // s
  // Advances one control period, delivering its outputs; false once the run is complete.
  bool step(SimSink& sink);

  // Whisk cycles completed, and those with at least one true contact; contact onsets per solid.
  int64_t cycles() const { return cycles_; }
  int64_t cycles_with_contact() const { return cycles_with_contact_; }
  const std::vector<int64_t>& onsets_per_solid() const { return onsets_per_solid_; }
  // Every configured fault (dead whiskers, board_offline, camera_blackout, camera_freeze,
  // odometry_slip, kidnap, each in the world file's order) and what it did so far.
  const std::vector<FaultRecord>& faults() const { return faults_; }

  const rcp::Controller& controller() const { return controller_; }
  const rcp::WhiskerPlant& plant() const { return plant_; }

 private:
  void update_obstacles(const Pose2& T_world_head);
  void update_faults(int64_t elapsed_us, int64_t utime);
  rcp::WhiskerSample sense(const rcp::WhiskerSample& plant_sample);
  void publish_camera(int64_t utime, std::vector<uint8_t> image, SimSink& sink);
  std::vector<uint8_t> render_frame(int64_t elapsed_us);

  World world_;
  RobotGeometry robot_;
  SimParams params_;
  rcp::Controller controller_;
  rcp::WhiskerPlant plant_;
  Renderer renderer_;
  FastRng camera_rng_;
  OdometryModel odometry_;
  int64_t total_steps_ = 0;
  int64_t step_ = 0;
  int64_t camera_period_us_ = 200000;
  int64_t next_camera_us_ = 0;
  int64_t camera_seq_ = 0;
  int64_t odometry_seq_ = 0;
  rcp::PerWhisker<double> command_{};
  rcp::PerWhisker<std::optional<WhiskerContact>> contacts_{};
  rcp::PerWhisker<bool> was_in_contact_{};
  int64_t cycles_ = 0;
  int64_t cycles_with_contact_ = 0;
  std::vector<int64_t> onsets_per_solid_;
  std::map<int64_t, ContactTruth> truth_;  // by cycle, until the cycle completes
  std::future<std::vector<uint8_t>> next_frame_;  // the frame at next_camera_us_, when render_ahead
  // Faults: the schedule, and what is active this period.
  std::vector<FaultRecord> faults_;
  std::vector<FaultEvent> fault_events_;  // beginnings and ends of this period, for the sink
  rcp::PerWhisker<bool> dead_{};
  std::array<bool, kNumBoards> board_offline_{};
  bool camera_blackout_ = false;
  bool camera_freeze_ = false;
  double odometry_slip_ = 1.0;
  WhiskerHealth health_;
  rcp::WhiskerSample last_sensed_;   // what a stale board repeats
  std::vector<uint8_t> held_image_;  // the last frame published: what a frozen camera repeats
};

}  // namespace whiskeye::sim
