// Whisk-cycle assembler (see cycle_assembler.h).
#include <whiskeye/rcp/cycle_assembler.h>

#include <limits>
#include <utility>

namespace whiskeye::rcp {

CycleAssembler::CycleAssembler(int64_t sample_period_us, int expected_samples)
    : period_us_(sample_period_us > 0 ? sample_period_us : 1), expected_samples_(expected_samples) {
  current_.samples.reserve(static_cast<std::size_t>(expected_samples_ + 16));
}

void CycleAssembler::append_missing(int64_t utime, Phase phase) {
  WhiskCycle::Sample& s = current_.samples.emplace_back();
  s.utime = utime;
  s.valid = false;
  s.phase = phase;
  ++current_.num_missing;
  if (current_.samples.size() == 1) current_.utime_start = utime;
  current_.utime_end = utime;
}

void CycleAssembler::start_cycle(const CycleTag& tag) {
  current_.cycle = tag.cycle;
  current_.samples.clear();
  current_.num_missing = 0;
  current_.utime_start = 0;
  current_.utime_end = 0;
  current_tag_ = tag;
  have_current_ = true;
  current_partial_ = false;
}

void CycleAssembler::recycle(WhiskCycle&& used) {
  if (used.samples.capacity() > spare_.capacity()) spare_.swap(used.samples);
}

void CycleAssembler::discard() {
  if (have_current_) ++discarded_;
  have_current_ = false;
  have_last_ = false;
  current_.samples.clear();
  current_.num_missing = 0;
}

// Ends the cycle in progress (emitting it into `done` if it is complete) and starts `tag`'s.
void CycleAssembler::roll(const CycleTag& tag, std::optional<WhiskCycle>& done) {
  if (have_current_) {
    if (tag.cycle > current_.cycle + 1) lost_cycles_ += tag.cycle - current_.cycle - 1;
    if (current_partial_ || current_.samples.empty()) {
      ++discarded_;
    } else {
      done = std::move(current_);
      current_ = WhiskCycle{};
      if (spare_.capacity() > 0) {
        current_.samples.swap(spare_);
        current_.samples.clear();
      } else {
        current_.samples.reserve(static_cast<std::size_t>(expected_samples_ + 16));
      }
    }
  }
  start_cycle(tag);
}

std::optional<WhiskCycle> CycleAssembler::push(const WhiskerSample& sample, const CycleTag& tag,
                                               const PerWhisker<bool>& contact) {
  if (have_last_ && (sample.seq <= last_seq_ || sample.utime <= last_utime_)) {
    ++rejected_;
    return std::nullopt;
  }
  std::optional<WhiskCycle> done;

  // Lost samples between the last one and this one, at evenly spaced expected times; those before
  // this cycle's start still belong to the previous cycle.
  const int64_t gap = have_last_ ? sample.seq - last_seq_ - 1 : 0;
  for (int64_t k = 1; k <= gap; ++k) {
    const int64_t t = last_utime_ + (sample.utime - last_utime_) * k / (gap + 1);
    if (have_current_ && current_.cycle != tag.cycle && t < tag.cycle_start_utime) {
      append_missing(t, t < current_tag_.retract_start_utime ? Phase::Protract : Phase::Retract);
      continue;
    }
    if (!have_current_ || current_.cycle != tag.cycle) roll(tag, done);
    append_missing(t, t < tag.retract_start_utime ? Phase::Protract : Phase::Retract);
  }

  if (!have_current_ || current_.cycle != tag.cycle) {
    const bool first = !have_current_ && !have_last_;
    roll(tag, done);
    // A cycle whose beginning was never seen is not a complete cycle.
    current_partial_ = first && sample.utime - tag.cycle_start_utime >= period_us_;
  }

  WhiskCycle::Sample& s = current_.samples.emplace_back();
  s.utime = sample.utime;
  s.valid = true;
  s.phase = tag.phase;
  for (int w = 0; w < kNumWhiskers; ++w) {
    // A whisker not measured in this sample (stale board, fault) is NaN, not a made-up 0 rad with
    // no deflection: a consumer skips it (slamd's tactile template does).
    constexpr float kMissing = std::numeric_limits<float>::quiet_NaN();
    s.theta[w] = sample.valid[w] ? static_cast<float>(sample.theta[w]) : kMissing;
    s.deflection_x[w] = sample.valid[w] ? static_cast<float>(sample.deflection_x[w]) : kMissing;
    s.deflection_y[w] = sample.valid[w] ? static_cast<float>(sample.deflection_y[w]) : kMissing;
    s.contact[w] = contact[w];
  }
  if (current_.samples.size() == 1) current_.utime_start = sample.utime;
  current_.utime_end = sample.utime;

  have_last_ = true;
  last_seq_ = sample.seq;
  last_utime_ = sample.utime;
  return done;
}

}  // namespace whiskeye::rcp
