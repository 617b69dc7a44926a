// Fuzz target: the LCM log reader (common's LogReader, which `slamd --replay` and vita-eval use):
// event headers, resynchronisation after damage, and the damage report. The input is also read as a
// file in chunks (LogReader::Access::kStreamed, from a memfd, the chunk size taken from the input's
// first byte), also with the first event's channel deferred (LogReader::defer, its data read in two
// parts), and must give exactly what the whole input in memory gives.
// Seeds: fuzz/corpus/lcm_log, a few events of a simulator log (fuzz_make_seeds).
#include "whiskeye/common/bus.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

using namespace whiskeye;

namespace {

using Events = std::vector<std::tuple<int64_t, std::string, std::vector<uint8_t>>>;

// `deferred`: the channel whose large events' data the reader defers; their rest is read first.
Events read_all(LogReader& reader, const std::string& deferred = "") {
  Events events;
  LogReader::EventView ev;
  while (reader.next(ev)) {
    if (!deferred.empty() && ev.channel == deferred) {
      // A part first (a crop's rows), then the rest: together the whole data.
      reader.read_rest(ev.owner, ev.data.first(ev.data.size() / 2));
      reader.read_rest(ev.owner);
    }
    events.emplace_back(ev.utime, std::string(ev.channel), std::vector<uint8_t>(ev.data.begin(), ev.data.end()));
  }
  return events;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  LogReader reader(std::span<const uint8_t>(data, size), "fuzz.lcmlog");
  LogReader::EventView ev;
  size_t payload = 0;
  Events events;
  while (reader.next(ev)) {
    // Every event lies inside the input.
    if (ev.data.data() < data || ev.data.data() + ev.data.size() > data + size) std::abort();
    if (ev.channel.empty()) std::abort();
    payload += ev.data.size() + ev.channel.size();
    if (reader.progress() < 0.0 || reader.progress() > 1.0) std::abort();
    events.emplace_back(ev.utime, std::string(ev.channel), std::vector<uint8_t>(ev.data.begin(), ev.data.end()));
  }
  const auto& damage = reader.damage();
  if (damage.damaged() != !damage.summary().empty()) std::abort();
  if (payload + damage.skipped_bytes > size) std::abort();
  if (damage.wild_times > 0 && damage.first_problem.empty()) std::abort();

  // The same bytes as a file, read in chunks of 1–256 bytes.
  static const int fd = ::memfd_create("fuzz.lcmlog", 0);
  if (fd < 0) std::abort();
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) std::abort();
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  LogReader streamed(path, LogReader::Access::kStreamed, size > 0 ? 1 + data[0] : 1);
  if (read_all(streamed) != events) std::abort();
  const auto& d = streamed.damage();
  if (d.skipped_bytes != damage.skipped_bytes || d.damaged_places != damage.damaged_places ||
      d.truncated_tail != damage.truncated_tail || d.wild_times != damage.wild_times ||
      streamed.progress() != reader.progress()) {
    std::abort();
  }
  // With the data of the first event's channel deferred past its first bytes (a replay's camera
  // frames), the same events.
  if (!events.empty()) {
    const std::string channel = std::get<1>(events.front());
    LogReader deferring(path, LogReader::Access::kStreamed, size > 0 ? 1 + data[0] : 1);
    deferring.defer(channel, size > 1 ? data[1] % 64 : 0);
    if (read_all(deferring, channel) != events || deferring.damage().skipped_bytes != damage.skipped_bytes) std::abort();
  }
  // The messages name the file; what follows the name is the same.
  const std::string memory_prefix = "fuzz.lcmlog: ", file_prefix = path + ": ";
  if (damage.first_problem.empty() ? !d.first_problem.empty()
                                   : d.first_problem.substr(0, file_prefix.size()) != file_prefix ||
                                         d.first_problem.substr(file_prefix.size()) !=
                                             damage.first_problem.substr(memory_prefix.size())) {
    std::abort();
  }
  return 0;
}
