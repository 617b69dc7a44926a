// Fuzz target: the LCM log reader (common's LogReader, which `slamd --replay` and vita-eval use):
// event headers, resynchronisation after damage, and the damage report.
// Seeds: fuzz/corpus/lcm_log, a few events of a simulator log (fuzz_make_seeds).
#include "whiskeye/common/bus.h"

#include <cstdlib>

using namespace whiskeye;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  LogReader reader(std::span<const uint8_t>(data, size), "fuzz.lcmlog");
  LogReader::EventView ev;
  size_t payload = 0;
  while (reader.next(ev)) {
    // Every event lies inside the input.
    if (ev.data.data() < data || ev.data.data() + ev.data.size() > data + size) std::abort();
    if (ev.channel.empty()) std::abort();
    payload += ev.data.size() + ev.channel.size();
    if (reader.progress() < 0.0 || reader.progress() > 1.0) std::abort();
  }
  const auto& damage = reader.damage();
  if (damage.damaged() != !damage.summary().empty()) std::abort();
  if (payload + damage.skipped_bytes > size) std::abort();
  if (damage.wild_times > 0 && damage.first_problem.empty()) std::abort();
  return 0;
}
