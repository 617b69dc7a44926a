// Whisk-cycle assembler: collects every sample of a whisk cycle and emits the complete cycle when
// the next one starts. Lost samples (sequence gaps) are inserted as invalid, zero-valued samples at
// their expected times; nothing is interpolated. Usable alone (tag each sample with its cycle) or
// inside the Controller. push() allocates only when it emits a cycle (the next cycle's storage is
// reserved then).
#pragma once

#include <whiskeye/rcp/types.h>

#include <optional>

namespace whiskeye::rcp {

// Where a sample sits in the pattern. The boundaries let the assembler give inserted (missing)
// samples the right cycle and phase.
struct CycleTag {
  int64_t cycle = 0;                // cycle number of this sample
  int64_t cycle_start_utime = 0;    // time at which this cycle started
  int64_t retract_start_utime = 0;  // time at which this cycle's retraction starts
  Phase phase = Phase::Protract;    // phase of this sample
};

class CycleAssembler {
 public:
  // `sample_period_us` is the nominal sample period (2000 at 500 Hz); `expected_samples` sizes the
  // reservation (e.g. 500 at 500 Hz and 1 Hz).
  explicit CycleAssembler(int64_t sample_period_us = 2000, int expected_samples = 500);

  // Adds one sample. Returns the previous cycle when `tag.cycle` differs from it (complete: every
  // sample from its start to the last one before this sample, gaps marked). A sample whose seq or
  // utime does not increase is ignored and counted. If the cycle number jumps by more than one, the
  // cycles in between had no samples at all and are counted as lost, not emitted.
  std::optional<WhiskCycle> push(const WhiskerSample& sample, const CycleTag& tag,
                                 const PerWhisker<bool>& contact);

  // The first cycle seen after construction / discard() is emitted only if its first sample is
  // within one sample period of tag.cycle_start_utime (otherwise its beginning was never seen and
  // it is discarded, counted).
  // Gives back the storage of an emitted cycle once its user is done with it: the next emission
  // reuses it instead of allocating, so a loop that recycles every cycle never allocates.
  void recycle(WhiskCycle&& used);

  // Drops the cycle in progress (e.g. whisking stopped mid-cycle); counted as discarded.
  void discard();

  bool has_cycle() const { return have_current_; }
  int64_t current_cycle() const { return current_.cycle; }
  int64_t rejected_samples() const { return rejected_; }
  int64_t lost_cycles() const { return lost_cycles_; }
  int64_t discarded_cycles() const { return discarded_; }

 private:
  void append_missing(int64_t utime, Phase phase);
  void start_cycle(const CycleTag& tag);
  void roll(const CycleTag& tag, std::optional<WhiskCycle>& done);

  std::vector<WhiskCycle::Sample> spare_;
  int64_t period_us_;
  int expected_samples_;
  bool have_current_ = false;
  bool current_partial_ = false;
  WhiskCycle current_;
  CycleTag current_tag_;
  bool have_last_ = false;
  int64_t last_seq_ = 0;
  int64_t last_utime_ = 0;
  int64_t rejected_ = 0;
  int64_t lost_cycles_ = 0;
  int64_t discarded_ = 0;
};

}  // namespace whiskeye::rcp
