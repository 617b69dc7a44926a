// The closed-loop simulation (see simulator.h).
#include "whiskeye/sim/simulator.h"

#include "whiskeye/common/utime.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace whiskeye::sim {

namespace {

// Independent seeds for the plant, odometry and camera noise from one user seed.
uint64_t derive_seed(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

FaultRecord interval_record(FaultKind kind, const FaultInterval& f, int index, double value) {
  FaultRecord r;
  r.kind = kind;
  r.index = index;
  r.value = value;
  r.start_us = seconds_to_utime(f.start);
  r.end_us = seconds_to_utime(f.start + f.duration);
  return r;
}

bool active(const FaultRecord& r) { return r.began_utime >= 0 && r.ended_utime < 0; }

}  // namespace

const char* to_string(FaultKind kind) {
  switch (kind) {
    case FaultKind::DeadWhisker: return "dead_whiskers";
    case FaultKind::BoardOffline: return "board_offline";
    case FaultKind::CameraBlackout: return "camera_blackout";
    case FaultKind::CameraFreeze: return "camera_freeze";
    case FaultKind::OdometrySlip: return "odometry_slip";
    case FaultKind::Kidnap: return "kidnap";
  }
  return "unknown";
}

rcp::PlantParams plant_params_for(const RobotGeometry& robot, rcp::PlantParams base) {
  for (int w = 0; w < kNumWhiskers; ++w) base.whisker_length[w] = robot.whiskers[static_cast<std::size_t>(w)].length;
  return base;
}

Simulator::Simulator(const World& world, const RobotGeometry& robot, const rcp::ControllerParams& controller,
                     const rcp::PlantParams& plant, const SimParams& params)
    : world_(world),
      robot_(robot),
      params_(params),
      controller_(controller, params.period_us > 0 ? 1e6 / static_cast<double>(params.period_us) : kControlRateHz),
      plant_(plant_params_for(robot, plant), derive_seed(params.seed, 0)),
      renderer_(world_, robot_),
      camera_rng_(derive_seed(params.seed, 1)),
      odometry_(world.odometry, world.odometry.start_at_truth ? world.trajectory.pose_at(0.0) : Pose2{},
                derive_seed(params.seed, 2)) {
  if (params_.period_us <= 0 || params_.odometry_divider <= 0 || params_.contact_update_divider <= 0) {
    throw std::invalid_argument("simulator periods and dividers must be positive");
  }
  const double d = params_.duration > 0.0 ? params_.duration : world_.trajectory.laps * world_.trajectory.lap_time();
  total_steps_ = static_cast<int64_t>(std::ceil(d * 1e6 / static_cast<double>(params_.period_us) - 1e-9));
  camera_period_us_ = std::llround(1e6 / robot_.camera.fps);
  command_.fill(plant_.params().initial_theta);
  onsets_per_solid_.assign(world_.solids.size(), 0);
  controller_.enable();

  const Faults& f = world_.faults;
  for (int w : f.dead_whiskers) {
    if (w < 0 || w >= kNumWhiskers) throw std::invalid_argument("dead whisker index out of range");
    FaultRecord r;
    r.kind = FaultKind::DeadWhisker;
    r.index = w;
    r.end_us = std::numeric_limits<int64_t>::max();
    faults_.push_back(r);
  }
  for (const BoardOffline& b : f.board_offline) {
    if (b.board < 0 || b.board >= kNumBoards) throw std::invalid_argument("offline board out of range");
    faults_.push_back(interval_record(FaultKind::BoardOffline, b, b.board, 0.0));
  }
  for (const FaultInterval& i : f.camera_blackout) faults_.push_back(interval_record(FaultKind::CameraBlackout, i, -1, 0.0));
  for (const FaultInterval& i : f.camera_freeze) faults_.push_back(interval_record(FaultKind::CameraFreeze, i, -1, 0.0));
  for (const OdometrySlip& o : f.odometry_slip) faults_.push_back(interval_record(FaultKind::OdometrySlip, o, -1, o.scale));
  // A kidnap is an instant: it begins and never ends (the robot stays where it was put down).
  for (const Kidnap& k : f.kidnap) {
    FaultRecord r;
    r.kind = FaultKind::Kidnap;
    r.value = k.to_angle;
    r.start_us = seconds_to_utime(k.at);
    r.end_us = std::numeric_limits<int64_t>::max();
    faults_.push_back(r);
  }
}

Simulator::~Simulator() {
  if (next_frame_.valid()) next_frame_.wait();
}

std::vector<uint8_t> Simulator::render_frame(int64_t elapsed_us) {
  const double t = static_cast<double>(elapsed_us) * 1e-6;
  std::vector<uint8_t> image;
  renderer_.render(world_.base_pose_at(t), t, camera_rng_, image);
  return image;
}

double Simulator::duration() const { return static_cast<double>(total_steps_ * params_.period_us) * 1e-6; }

void Simulator::update_obstacles(const Pose2& T_world_head) {
  const double gain = plant_.params().deflection_gain;
  for (int w = 0; w < kNumWhiskers; ++w) {
    contacts_[w] = find_whisker_contact(world_, robot_, T_world_head, w, params_.sweep);
    if (!contacts_[w] || gain <= 0.0) {
      plant_.set_obstacle(w, std::nullopt);
      continue;
    }
    const WhiskerGeometry& g = robot_.whiskers[static_cast<std::size_t>(w)];
    rcp::Obstacle o;
    o.contact_angle = contacts_[w]->theta;
    o.radial_distance = contacts_[w]->radial;
    // The plant bends as gain · scale · Δθ · length / r; robot.yaml calibrates bend_gain · Δθ / r.
    o.stiffness_scale = contacts_[w]->stiffness * g.bend_gain / (gain * g.length);
    plant_.set_obstacle(w, o);
  }
}

// Which faults are active this period. Their beginnings and ends are queued for the sink (they go
// out after a completed cycle, which is stamped with the previous period), ends first: an interval
// may end exactly where the next one of its sensor begins.
void Simulator::update_faults(int64_t elapsed_us, int64_t utime) {
  dead_.fill(false);
  board_offline_.fill(false);
  camera_blackout_ = false;
  camera_freeze_ = false;
  odometry_slip_ = 1.0;
  fault_events_.clear();
  for (const bool ending : {true, false}) {
    for (FaultRecord& r : faults_) {
      const bool was = active(r);
      const bool now = elapsed_us >= r.start_us && elapsed_us < r.end_us;
      if (ending && was && !now) {
        r.ended_utime = utime;
        fault_events_.push_back({utime, r.kind, false, r.index, r.value, {}});
      } else if (!ending && now && !was) {
        r.began_utime = utime;
        FaultEvent e{utime, r.kind, true, r.index, r.value, {}};
        if (r.kind == FaultKind::Kidnap) {
          r.pose = world_.base_pose_at(static_cast<double>(elapsed_us) * 1e-6);
          e.value = 0.0;
          e.pose = r.pose;
        }
        fault_events_.push_back(e);
      }
    }
  }
  for (FaultRecord& r : faults_) {
    if (elapsed_us < r.start_us || elapsed_us >= r.end_us) continue;
    switch (r.kind) {
      case FaultKind::DeadWhisker:
        dead_[r.index] = true;
        ++r.affected;
        break;
      case FaultKind::BoardOffline:
        board_offline_[static_cast<std::size_t>(r.index)] = true;
        ++r.affected;
        break;
      case FaultKind::CameraBlackout: camera_blackout_ = true; break;
      case FaultKind::CameraFreeze: camera_freeze_ = true; break;
      case FaultKind::OdometrySlip: odometry_slip_ *= r.value; break;
      case FaultKind::Kidnap: break;  // in base_pose_at
    }
  }
}

// The plant's sample as whiskerd would hand it to the controller under the active faults: a dead
// whisker reads no deflection and is invalid; an offline board's whiskers repeat their last values
// and are invalid (stale). The controller and the cycle assembler then treat them as on the robot.
rcp::WhiskerSample Simulator::sense(const rcp::WhiskerSample& plant_sample) {
  rcp::WhiskerSample s = plant_sample;
  for (int w = 0; w < kNumWhiskers; ++w) {
    const bool stale = board_offline_[static_cast<std::size_t>(w / kWhiskersPerBoard)];
    health_.fault[w] = dead_[w];
    health_.stale[w] = stale;
    if (dead_[w]) {
      s.deflection_x[w] = 0.0;
      s.deflection_y[w] = 0.0;
    }
    if (stale) {
      s.theta[w] = last_sensed_.theta[w];
      s.deflection_x[w] = last_sensed_.deflection_x[w];
      s.deflection_y[w] = last_sensed_.deflection_y[w];
    }
    s.valid[w] = !dead_[w] && !stale;
  }
  last_sensed_ = s;
  return s;
}

// A blacked-out camera delivers nothing (seq counts published frames, so it shows no gap); a frozen
// one delivers the last frame it published before the freeze (or, frozen from its first frame on,
// that frame) at its normal rate. Frames are rendered either way: the camera noise stream, hence
// every later frame, is that of the same run without the fault.
void Simulator::publish_camera(int64_t utime, std::vector<uint8_t> image, SimSink& sink) {
  for (FaultRecord& r : faults_) {
    const bool applies = r.kind == FaultKind::CameraBlackout || (r.kind == FaultKind::CameraFreeze && !camera_blackout_);
    if (active(r) && applies) ++r.affected;
  }
  if (camera_blackout_) return;
  if (camera_freeze_) {
    if (held_image_.empty()) held_image_ = std::move(image);
    sink.camera(utime, camera_seq_++, held_image_, renderer_.width(), renderer_.height());
    return;
  }
  sink.camera(utime, camera_seq_++, image, renderer_.width(), renderer_.height());
  held_image_ = std::move(image);
}

bool Simulator::step(SimSink& sink) {
  if (step_ >= total_steps_) return false;
  const int64_t elapsed_us = step_ * params_.period_us;
  const int64_t utime = params_.start_utime + elapsed_us;
  const double t = static_cast<double>(elapsed_us) * 1e-6;
  const Pose2 T_world_base = world_.base_pose_at(t);
  const Pose2 T_world_head = compose(T_world_base, robot_.T_base_head);

  update_faults(elapsed_us, utime);
  // The whiskers meet what is around the robot where it was put down, from that period on.
  const bool kidnapped = std::any_of(fault_events_.begin(), fault_events_.end(),
                                     [](const FaultEvent& e) { return e.kind == FaultKind::Kidnap; });
  if (step_ % params_.contact_update_divider == 0 || kidnapped) update_obstacles(T_world_head);
  const rcp::WhiskerSample sample = sense(plant_.step(utime, command_));
  rcp::ControlOutput out = controller_.step(sample);
  command_ = out.theta_command;

  // A completed cycle ends at the previous sample: it goes out before this period's messages.
  if (out.completed_cycle) {
    const rcp::WhiskCycle& c = *out.completed_cycle;
    sink.whisk_cycle(c);
    ContactTruth truth;
    if (auto it = truth_.find(c.cycle); it != truth_.end()) truth = std::move(it->second);
    truth.cycle = c.cycle;
    truth.utime = c.utime_end;
    ++cycles_;
    if (!truth.points.empty()) ++cycles_with_contact_;
    sink.contact_truth(truth);
    truth_.erase(truth_.begin(), truth_.upper_bound(c.cycle));
    controller_.recycle(std::move(*out.completed_cycle));  // its storage serves the next cycle
    out.completed_cycle.reset();
  }
  // True contact onsets of this period, attributed to the controller's current cycle.
  const auto& state = plant_.true_state();
  for (int w = 0; w < kNumWhiskers; ++w) {
    if (state[w].in_contact && !was_in_contact_[w] && contacts_[w]) {
      truth_[out.cycle].points.push_back({w, utime, contacts_[w]->p_contact_in_head, contacts_[w]->solid});
      if (contacts_[w]->solid >= 0) ++onsets_per_solid_[static_cast<std::size_t>(contacts_[w]->solid)];
    }
    was_in_contact_[w] = state[w].in_contact;
  }

  for (const FaultEvent& e : fault_events_) sink.fault(e);
  sink.whisker_sample(sample, health_);
  sink.rcp_state(out);
  if (step_ % params_.odometry_divider == 0) {
    double vx;
    double vy;
    double omega;
    world_.trajectory.body_velocity(vx, vy, omega);
    // A slip is a scale error on the measured linear velocity, like scale_v (a wheel that turns
    // more or less than the base moves); the heading rate is measured as it is.
    vx *= odometry_slip_;
    vy *= odometry_slip_;
    for (FaultRecord& r : faults_) r.affected += r.kind == FaultKind::OdometrySlip && active(r);
    const double dt = step_ == 0 ? 0.0 : static_cast<double>(params_.odometry_divider * params_.period_us) * 1e-6;
    sink.odometry(utime, odometry_seq_++, odometry_.step(vx, vy, omega, dt));
    sink.ground_truth(utime, T_world_base);
  }
  if (elapsed_us >= next_camera_us_) {
    std::vector<uint8_t> image = next_frame_.valid() ? next_frame_.get() : render_frame(elapsed_us);
    next_camera_us_ += camera_period_us_;
    if (params_.render_ahead && next_camera_us_ < total_steps_ * params_.period_us) {
      // Rendered at the control period that will publish it (the first at or after its due time).
      const int64_t at = (next_camera_us_ + params_.period_us - 1) / params_.period_us * params_.period_us;
      next_frame_ = std::async(std::launch::async, [this, at] { return render_frame(at); });
    }
    publish_camera(utime, std::move(image), sink);
  }
  ++step_;
  return true;
}

}  // namespace whiskeye::sim
