// The closed-loop simulation (see simulator.h).
#include "whiskeye/sim/simulator.h"

#include <cmath>
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

}  // namespace

rcp::PlantParams plant_params_for(const RobotGeometry& robot, rcp::PlantParams base) {
  for (int w = 0; w < kNumWhiskers; ++w) base.whisker_length[w] = robot.whiskers[static_cast<std::size_t>(w)].length;
  return base;
}

Simulator::Simulator(const World& world, const RobotGeometry& robot, const rcp::ControllerParams& controller,
                     const rcp::PlantParams& plant, const SimParams& params)
    : world_(world),
      robot_(robot),
      params_(params),
      controller_(controller, params.period_us > 0 ? 1e6 / static_cast<double>(params.period_us) : 500.0),
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
}

Simulator::~Simulator() {
  if (next_frame_.valid()) next_frame_.wait();
}

std::vector<uint8_t> Simulator::render_frame(int64_t elapsed_us) {
  const double t = static_cast<double>(elapsed_us) * 1e-6;
  std::vector<uint8_t> image;
  renderer_.render(world_.trajectory.pose_at(t), t, camera_rng_, image);
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

bool Simulator::step(SimSink& sink) {
  if (step_ >= total_steps_) return false;
  const int64_t elapsed_us = step_ * params_.period_us;
  const int64_t utime = params_.start_utime + elapsed_us;
  const double t = static_cast<double>(elapsed_us) * 1e-6;
  const Pose2 T_world_base = world_.trajectory.pose_at(t);
  const Pose2 T_world_head = compose(T_world_base, robot_.T_base_head);

  if (step_ % params_.contact_update_divider == 0) update_obstacles(T_world_head);
  const rcp::WhiskerSample sample = plant_.step(utime, command_);
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

  sink.whisker_sample(sample);
  sink.rcp_state(out);
  if (step_ % params_.odometry_divider == 0) {
    double vx;
    double vy;
    double omega;
    world_.trajectory.body_velocity(vx, vy, omega);
    const double dt = step_ == 0 ? 0.0 : static_cast<double>(params_.odometry_divider * params_.period_us) * 1e-6;
    sink.odometry(utime, odometry_seq_++, odometry_.step(vx, vy, omega, dt));
    sink.ground_truth(utime, T_world_base);
  }
  if (elapsed_us >= next_camera_us_) {
    const std::vector<uint8_t> image = next_frame_.valid() ? next_frame_.get() : render_frame(elapsed_us);
    next_camera_us_ += camera_period_us_;
    if (params_.render_ahead && next_camera_us_ < total_steps_ * params_.period_us) {
      // Rendered at the control period that will publish it (the first at or after its due time).
      const int64_t at = (next_camera_us_ + params_.period_us - 1) / params_.period_us * params_.period_us;
      next_frame_ = std::async(std::launch::async, [this, at] { return render_frame(at); });
    }
    sink.camera(utime, camera_seq_++, image, renderer_.width(), renderer_.height());
  }
  ++step_;
  return true;
}

}  // namespace whiskeye::sim
