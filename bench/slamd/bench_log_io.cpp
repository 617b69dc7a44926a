// log-io-bench: what reading a recorded LCM log costs this machine, against a plain read() of the
// same file (figures in docs/performance.md, "### Replay"). The file is a synthetic log with the
// default arena's mix (every 200 ms: 100 WHISKER_SAMPLE of 526 B, 100 RCP_STATE of 363 B, 10
// ODOMETRY of 108 B and one 614 kB CAMERA frame), 128 MiB, written once into ${TMPDIR:-/tmp} and
// read from the page cache, so no benchmark waits for a disk.
//   BM_ReadWholeFile        the reference: read() of the whole file into one reused 1 MiB buffer
//   BM_TouchMappedPages     mmap the file and read one byte of every 4 KiB page: the price of
//                           mapping a page, which every walk over a fresh mapping pays
//   BM_LogReaderWalk/A      LogReader handing out every event, A = 0: kMapped (a mapping), 1:
//                           kStreamed (pread into reused chunks); only the headers are read, as a
//                           replay does with the events it skips
//   BM_LogReaderWalkSmall/A the same, and every event under 64 kB read in full (what a replay
//                           decodes: samples, odometry, whisk cycles), frames left alone
//   BM_LogReaderWalkAll/A   the same, and every event read in full, frames too
// Counters: s_per_page, the CPU time per 4 KiB of the file, and bytes_per_second of the file.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include <whiskeye/common/bus.h>

namespace whiskeye {
namespace {

constexpr std::size_t kFileBytes = std::size_t{128} << 20;
constexpr std::size_t kPage = 4096;

std::string g_path;

void write_log(const std::string& path) {
  LogWriterBus log(path);
  const std::vector<uint8_t> sample(526 - 28 - 14, 1), rcp(363 - 28 - 9, 2), odometry(108 - 28 - 8, 3),
      frame(614478 - 28 - 6, 4);
  int64_t t = 1'700'000'000'000'000;
  std::size_t bytes = 0;
  while (bytes < kFileBytes) {
    for (int i = 0; i < 100; ++i) {
      log.set_time(t += 1000);
      log.publish_raw("WHISKER_SAMPLE", sample);
      log.publish_raw("RCP_STATE", rcp);
      bytes += 526 + 363;
      if (i % 10 == 0) {
        log.publish_raw("ODOMETRY", odometry);
        bytes += 108;
      }
    }
    log.publish_raw("CAMERA", frame);
    bytes += 614478;
  }
}

std::size_t file_size() { return std::filesystem::file_size(g_path); }

void set_counters(benchmark::State& state, std::size_t bytes) {
  state.SetBytesProcessed(static_cast<int64_t>(bytes) * state.iterations());
  // Pages over CPU time, inverted: seconds per page of the file.
  state.counters["s_per_page"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(bytes / kPage),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_ReadWholeFile(benchmark::State& state) {
  std::vector<char> buffer(std::size_t{1} << 20);
  const std::size_t size = file_size();
  for (auto _ : state) {
    const int fd = ::open(g_path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error("open " + g_path);
    std::size_t got = 0;
    ssize_t r;
    while ((r = ::read(fd, buffer.data(), buffer.size())) > 0) got += static_cast<std::size_t>(r);
    ::close(fd);
    if (got != size) throw std::runtime_error("short read of " + g_path);
    benchmark::DoNotOptimize(buffer.data());
  }
  set_counters(state, size);
}
BENCHMARK(BM_ReadWholeFile)->Unit(benchmark::kMillisecond);

void BM_TouchMappedPages(benchmark::State& state) {
  const std::size_t size = file_size();
  for (auto _ : state) {
    const int fd = ::open(g_path.c_str(), O_RDONLY | O_CLOEXEC);
    void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    ::close(fd);
    if (p == MAP_FAILED) throw std::runtime_error("mmap " + g_path);
    ::madvise(p, size, MADV_SEQUENTIAL);  // as LogReader does
    const auto* bytes = static_cast<const volatile uint8_t*>(p);
    unsigned sum = 0;
    for (std::size_t at = 0; at < size; at += kPage) sum += bytes[at];
    benchmark::DoNotOptimize(sum);
    ::munmap(p, size);
  }
  set_counters(state, size);
}
BENCHMARK(BM_TouchMappedPages)->Unit(benchmark::kMillisecond);

void walk(benchmark::State& state, LogReader::Access access, std::size_t read_in_full_below) {
  const std::size_t size = file_size();
  for (auto _ : state) {
    LogReader reader(g_path, access);
    LogReader::EventView event;
    uint64_t sum = 0;
    while (reader.next(event)) {
      sum += event.channel.size();
      if (event.data.size() < read_in_full_below) {
        sum = std::accumulate(event.data.begin(), event.data.end(), sum);
      }
    }
    benchmark::DoNotOptimize(sum);
  }
  set_counters(state, size);
}

// Argument: 0 kMapped, 1 kStreamed.
LogReader::Access access(const benchmark::State& state) {
  return state.range(0) == 0 ? LogReader::Access::kMapped : LogReader::Access::kStreamed;
}

void BM_LogReaderWalk(benchmark::State& state) { walk(state, access(state), 0); }
BENCHMARK(BM_LogReaderWalk)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_LogReaderWalkSmall(benchmark::State& state) { walk(state, access(state), 64 * 1024); }
BENCHMARK(BM_LogReaderWalkSmall)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Every event read in full, the frames too: a frame a replay uses costs a mapping its pages.
void BM_LogReaderWalkAll(benchmark::State& state) { walk(state, access(state), SIZE_MAX); }
BENCHMARK(BM_LogReaderWalkAll)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace whiskeye

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  const char* tmp = std::getenv("TMPDIR");
  whiskeye::g_path = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/log-io-bench-" +
                     std::to_string(::getpid()) + ".lcmlog";
  whiskeye::write_log(whiskeye::g_path);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::filesystem::remove(whiskeye::g_path);
  return 0;
}
