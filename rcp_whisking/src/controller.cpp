// The whisking controller (see controller.h): pattern -> contact detection -> RCP ceiling ->
// command slew limit, and the whisk-cycle assembly, once per sample.
#include <whiskeye/rcp/controller.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace whiskeye::rcp {

namespace {

constexpr double kNoHold = std::numeric_limits<double>::infinity();

// Cubic smoothstep of the linear ramp state, so the amplitude starts and ends with zero slope.
double smooth(double s) { return s * s * (3.0 - 2.0 * s); }

// First utime at or after `cycles` whisk cycles from `origin` at frequency f.
int64_t utime_at(int64_t origin, double cycles, double frequency_hz) {
  return origin + static_cast<int64_t>(std::ceil(cycles * 1e6 / frequency_hz - 1e-6));
}

double valid_rate(double sample_rate_hz) {
  if (!(sample_rate_hz > 0.0 && sample_rate_hz <= 1e6)) {
    throw ParamError("controller sample rate " + std::to_string(sample_rate_hz) + " Hz must be in (0, 1e6]");
  }
  return sample_rate_hz;
}

int64_t sample_period_us(double sample_rate_hz) {
  return std::max<int64_t>(1, std::llround(1e6 / valid_rate(sample_rate_hz)));
}

}  // namespace

Controller::Controller(const ControllerParams& params, double sample_rate_hz)
    : params_(params),
      nominal_period_s_(1.0 / valid_rate(sample_rate_hz)),
      pattern_(params.pattern),
      detector_(params.detector),
      assembler_(sample_period_us(sample_rate_hz),
                 static_cast<int>(std::ceil(valid_rate(sample_rate_hz) / params.pattern.frequency_hz))) {
  validate(params_);
  command_.fill(params_.pattern.theta_rest);
  for (int w = 0; w < kNumWhiskers; ++w) reset_cycle_state(w);
  row_cycle_.fill(std::numeric_limits<int64_t>::min());
  if (params_.detector.learn_cycles == 0) detector_.finish_learning();
  out_.theta_command = command_;
  out_.theta_nominal = command_;
  out_.theta_ceiling = ceiling_;
}

void Controller::reset_cycle_state(int w) {
  contact_max_[w] = 0.0;
  hold_[w] = kNoHold;
  ceiling_[w] = params_.pattern.theta_max;
}

void Controller::enable() { enabled_ = true; }

bool Controller::at_rest() const {
  if (running_) return false;
  return std::all_of(command_.begin(), command_.end(),
                     [&](double c) { return std::abs(c - params_.pattern.theta_rest) <= 1e-9; });
}
void Controller::disable() { enabled_ = false; }

ControlOutput Controller::step(const WhiskerSample& sample) {
  if (have_last_ && sample.utime <= last_utime_) {
    // Time must advance; a repeated or reordered sample changes nothing.
    ++stats_.rejected_samples;
    return out_;
  }
  ++stats_.steps;
  const double dt = have_last_ ? static_cast<double>(sample.utime - last_utime_) * 1e-6 : 0.0;
  if (have_last_ && sample.seq > last_seq_ + 1) stats_.missing_samples += sample.seq - last_seq_ - 1;
  have_last_ = true;
  last_utime_ = sample.utime;
  last_seq_ = sample.seq;

  const PatternParams& pp = params_.pattern;
  const RcpParams& rp = params_.rcp;

  // Start, ramp, stop.
  bool starting = false;
  if (enabled_ && !running_) {
    running_ = true;
    starting = true;
    origin_utime_ = sample.utime;
    origin_cycle_ = out_.cycle;
    envelope_ = 0.0;
    row_cycle_.fill(std::numeric_limits<int64_t>::min());
  }
  if (running_ && !starting) {
    const double step = pp.ramp_time > 0.0 ? dt / pp.ramp_time : 1.0;
    envelope_ += enabled_ ? step : -step;
    // Snap the ends so rounding of the summed steps cannot leave the ramp a hair short.
    if (envelope_ >= 1.0 - 1e-9) envelope_ = 1.0;
    if (envelope_ <= 1e-9) envelope_ = 0.0;
    if (!enabled_ && envelope_ == 0.0) {
      running_ = false;
      if (assembler_.has_cycle()) ++stats_.cycles_discarded;
      assembler_.discard();
      for (int w = 0; w < kNumWhiskers; ++w) reset_cycle_state(w);
    }
  }

  double phase = 0.0;
  int64_t cycle = out_.cycle;
  Phase master = Phase::Rest;
  if (running_) {
    phase = static_cast<double>(sample.utime - origin_utime_) * pp.frequency_hz / 1e6;
    const double n = std::floor(phase);
    cycle = origin_cycle_ + 1 + static_cast<int64_t>(n);
    master = pattern_.protracting(phase) ? Phase::Protract : Phase::Retract;
    if (cycle != out_.cycle && enabled_) {
      ++free_cycles_;
      // learn_cycles complete cycles have been seen once the (learn_cycles + 1)-th starts.
      if (!detector_.learned() && free_cycles_ > params_.detector.learn_cycles) detector_.finish_learning();
    }
  }

  detector_.update(sample, running_ && enabled_ && !detector_.learned());
  const PerWhisker<bool>& in_contact = detector_.in_contact();
  const PerWhisker<double>& level = detector_.level();

  const double amplitude = smooth(envelope_);
  // A late sample (a stall, a loop that runs without real-time priority) must not license a step:
  // the slew step is bounded by two nominal periods, however long the gap was.
  const double max_step = pp.max_rate * std::min(dt, 2.0 * nominal_period_s_);
  for (int r = 0; r < kWhiskerRows; ++r) {
    double nominal = pp.theta_rest;
    bool protracting = false;
    int64_t row_cycle = 0;
    if (running_) {
      const double rph = pattern_.row_phase(phase, r);
      row_cycle = static_cast<int64_t>(std::floor(rph));
      protracting = pattern_.protracting(rph);
      nominal = pp.theta_rest + amplitude * (pattern_.theta(rph) - pp.theta_rest);
    }
    for (int c = 0; c < kWhiskerColumns; ++c) {
      const int w = r * kWhiskerColumns + c;
      if (running_ && row_cycle != row_cycle_[w]) {
        // Each whisker's ceiling resets at the start of its own (row) cycle.
        row_cycle_[w] = row_cycle;
        reset_cycle_state(w);
      }
      if (running_ && rp.law != RcpLaw::Off && protracting && in_contact[w]) {
        if (rp.freeze_on_contact && hold_[w] == kNoHold) hold_[w] = command_[w];
        if (rp.law == RcpLaw::Whiskeye) {
          contact_max_[w] = std::max(contact_max_[w], level[w]);
        } else {
          const double from = std::min(ceiling_[w], command_[w]);
          ceiling_[w] = std::max(rp.theta_rcp, from - rp.rate_limit * level[w] * dt);
        }
      }
      if (rp.law == RcpLaw::Whiskeye) {
        ceiling_[w] = std::min(pp.theta_max + contact_max_[w] * (rp.theta_rcp - pp.theta_max), hold_[w]);
      } else if (rp.law == RcpLaw::RateLimited) {
        ceiling_[w] = std::min(ceiling_[w], hold_[w]);
      }
      double target = std::min(nominal, ceiling_[w]);
      target = std::clamp(target, -pp.theta_limit, pp.theta_limit);
      // Slew limit: the command never steps (enable, disable, ceiling reset at cycle start).
      const double prev = command_[w];
      command_[w] = std::clamp(target, prev - max_step, prev + max_step);
      out_.theta_nominal[w] = nominal;
    }
  }

  out_.utime = sample.utime;
  out_.cycle = cycle;
  out_.phase = master;
  out_.cycle_phase = running_ ? phase - std::floor(phase) : 0.0;
  out_.enabled = enabled_;
  out_.theta_command = command_;
  out_.theta_ceiling = ceiling_;
  out_.contact = level;
  out_.in_contact = in_contact;
  out_.completed_cycle.reset();

  if (running_) {
    const double n = std::floor(phase);
    CycleTag tag;
    tag.cycle = cycle;
    tag.cycle_start_utime = utime_at(origin_utime_, n, pp.frequency_hz);
    tag.retract_start_utime = utime_at(origin_utime_, n + pp.protraction_fraction, pp.frequency_hz);
    tag.phase = master;
    std::optional<WhiskCycle> done = assembler_.push(sample, tag, in_contact);
    if (done) {
      ++stats_.cycles_emitted;
      ControlOutput result = out_;
      result.completed_cycle = std::move(done);
      return result;
    }
  }
  return out_;
}

}  // namespace whiskeye::rcp
