// LCM log files: LogWriterBus writes them, LogReader (common/log_reader.h) reads them back, mapped
// or streamed, through damage.
#include "scratch.h"
#include "whiskeye/common/bus.h"
#include "whiskeye/common/log_reader.h"

#include <whiskeye/pose2d_t.hpp>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <map>
#include <random>
#include <tuple>

namespace whiskeye {
namespace {

TEST(LogFiles, WriterAndReaderRoundTrip) {
  const std::string path = whiskeye::testing::scratch_file("bus_roundtrip", ".lcmlog");
  {
    LogWriterBus out(path);
    for (int i = 0; i < 5; ++i) {
      out.set_time(1000 + i);
      pose2d_t p{};
      p.utime = i;
      p.theta = 0.1 * i;
      publish(out, "GROUND_TRUTH", p);
    }
    EXPECT_EQ(out.events_written(), 5);
  }
  LogReader in(path);
  LogEvent ev;
  int n = 0;
  while (in.next(ev)) {
    pose2d_t p;
    ASSERT_TRUE(decode_message(ev.data, p));
    EXPECT_EQ(ev.channel, "GROUND_TRUTH");
    EXPECT_EQ(ev.utime, 1000 + n);
    EXPECT_EQ(p.utime, n);
    ++n;
  }
  EXPECT_EQ(n, 5);
  EXPECT_DOUBLE_EQ(in.progress(), 1.0);
}

TEST(LogFiles, ViewsReadTheSameEventsWithoutCopying) {
  const std::string path = whiskeye::testing::scratch_file("bus_views", ".lcmlog");
  {
    LogWriterBus out(path);
    for (int i = 0; i < 3; ++i) {
      out.set_time(10 * i);
      pose2d_t p{};
      p.x = i;
      publish(out, i == 1 ? "B" : "A", p);
    }
  }
  LogReader in(path);
  LogReader::EventView ev;
  std::vector<std::string> channels;
  std::vector<double> xs;
  while (in.next(ev)) {
    pose2d_t p;
    ASSERT_TRUE(decode_message(ev.data, p));
    channels.emplace_back(ev.channel);
    xs.push_back(p.x);
    EXPECT_EQ(ev.utime, static_cast<int64_t>(10 * p.x));
  }
  EXPECT_EQ(channels, (std::vector<std::string>{"A", "B", "A"}));
  EXPECT_EQ(xs, (std::vector<double>{0, 1, 2}));
}

// Writes three pose2d_t events on "A" and returns the file's bytes.
std::vector<char> three_event_log(const std::string& path) {
  {
    LogWriterBus out(path);
    for (int i = 0; i < 3; ++i) {
      out.set_time(i);
      pose2d_t p{};
      p.x = i;
      publish(out, "A", p);
    }
  }
  std::ifstream f(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(f), {});
}

void write_bytes(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Reads every event; returns the x of each (pose2d_t on "A") and the reader's damage report.
std::pair<std::vector<double>, LogReader::Damage> read_all(const std::string& path) {
  LogReader in(path);
  LogReader::EventView ev;
  std::vector<double> xs;
  while (in.next(ev)) {
    pose2d_t p{};
    EXPECT_EQ(p.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())), static_cast<int>(ev.data.size()));
    xs.push_back(p.x);
  }
  EXPECT_FALSE(in.next(ev)) << "stays at the end";
  return {xs, in.damage()};
}

TEST(LogFiles, ALogCutOffInsideItsLastEventYieldsEveryCompleteEventAndSaysWhere) {
  const std::string path = whiskeye::testing::scratch_file("bus_truncated", ".lcmlog");
  std::vector<char> bytes = three_event_log(path);
  const size_t event = bytes.size() / 3;  // equal events
  auto [xs, damage] = read_all(path);
  EXPECT_EQ(xs, (std::vector<double>{0, 1, 2}));
  EXPECT_FALSE(damage.damaged());
  EXPECT_EQ(damage.summary(), "");
  bytes.resize(bytes.size() - 5);  // the last event loses 5 bytes of data (a logger killed mid-write)
  write_bytes(path, bytes);
  std::tie(xs, damage) = read_all(path);
  EXPECT_EQ(xs, (std::vector<double>{0, 1}));
  EXPECT_TRUE(damage.truncated_tail);
  EXPECT_EQ(damage.skipped_bytes, event - 5);
  EXPECT_EQ(damage.damaged_places, 1);
  const std::string s = damage.summary();
  EXPECT_NE(s.find(path + ": truncated LCM log: the event at byte " + std::to_string(2 * event)), std::string::npos) << s;
  EXPECT_NE(s.find("the last event cut off"), std::string::npos) << s;
  bytes.resize(2 * event + 10);  // and in the middle of a header
  write_bytes(path, bytes);
  std::tie(xs, damage) = read_all(path);
  EXPECT_EQ(xs, (std::vector<double>{0, 1}));
  EXPECT_TRUE(damage.truncated_tail);
  EXPECT_NE(damage.summary().find("incomplete event header"), std::string::npos) << damage.summary();
}

TEST(LogFiles, ACorruptEventIsSkippedAndReadingResumesAtTheNextEvent) {
  const std::string path = whiskeye::testing::scratch_file("bus_corrupt", ".lcmlog");
  const std::vector<char> good = three_event_log(path);
  const size_t event = good.size() / 3;
  struct Case {
    size_t byte;
    char value;
    std::string problem;
  };
  for (const Case& c : {Case{event, 0x00, "no event sync word at byte " + std::to_string(event)},
                        Case{event + 24, static_cast<char>(0x80), "data length"},  // negative
                        Case{event + 20, 0x7f, "channel length"}}) {          // far beyond the file
    std::vector<char> bad = good;
    bad[c.byte] = c.value;  // the second event's header
    write_bytes(path, bad);
    auto [xs, damage] = read_all(path);
    EXPECT_EQ(xs, (std::vector<double>{0, 2})) << c.problem << ": the first and third events survive";
    EXPECT_EQ(damage.skipped_bytes, event) << c.problem;
    EXPECT_EQ(damage.damaged_places, 1);
    EXPECT_FALSE(damage.truncated_tail);
    EXPECT_NE(damage.summary().find(path + ": corrupt LCM log: "), std::string::npos) << damage.summary();
    EXPECT_NE(damage.summary().find(c.problem), std::string::npos) << damage.summary();
  }
  // Garbage between events (a sync word inside it that starts no plausible event is passed over).
  std::vector<char> bad(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(event));
  const char junk[] = {1, 2, static_cast<char>(0xED), static_cast<char>(0xA1), static_cast<char>(0xDA), 1, 0, 0, 0};
  bad.insert(bad.end(), junk, junk + sizeof junk);
  bad.insert(bad.end(), good.begin() + static_cast<std::ptrdiff_t>(event), good.end());
  write_bytes(path, bad);
  auto [xs, damage] = read_all(path);
  EXPECT_EQ(xs, (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(damage.skipped_bytes, sizeof junk);
}

// Event times of a log written at 50 Hz from kT0, with `changed` (index → time) in place of some.
std::vector<int64_t> read_times(const std::string& name, int n, const std::map<int, int64_t>& changed,
                                LogReader::Damage* damage = nullptr) {
  constexpr int64_t kT0 = 1'700'000'000'000'000;
  const std::string path = whiskeye::testing::scratch_file(name, ".lcmlog");
  {
    LogWriterBus out(path);
    for (int i = 0; i < n; ++i) {
      const auto it = changed.find(i);
      out.set_time(it != changed.end() ? it->second : kT0 + i * 20'000);
      publish(out, "GROUND_TRUTH", pose2d_t{});
    }
  }
  LogReader in(path);
  std::vector<int64_t> times;
  LogEvent ev;
  while (in.next(ev)) times.push_back(ev.utime - kT0);
  if (damage) *damage = in.damage();
  return times;
}

// A bit flip in one event's time made a replay report 35 million seconds of data and stamp its
// outputs with it. One time out of line with both neighbours is damage: counted, reported, replaced.
TEST(LogFiles, ASingleWildEventTimeIsDamageAndTakesThePreviousTime) {
  constexpr int64_t kT0 = 1'700'000'000'000'000;
  LogReader::Damage damage;
  const auto times = read_times("bus_wild", 5, {{2, kT0 + 40'000 + (int64_t{1} << 45)}}, &damage);
  EXPECT_EQ(times, (std::vector<int64_t>{0, 20'000, 20'000, 60'000, 80'000}));
  EXPECT_TRUE(damage.damaged());
  EXPECT_EQ(damage.wild_times, 1);
  EXPECT_NE(damage.summary().find("event time " + std::to_string(kT0 + 40'000 + (int64_t{1} << 45)) + " us at byte"),
            std::string::npos)
      << damage.summary();
  EXPECT_NE(damage.summary().find("1 event time(s) out of line"), std::string::npos) << damage.summary();
  // Flipped down, and on the first event.
  EXPECT_EQ(read_times("bus_wild_low", 4, {{1, kT0 + 20'000 - (int64_t{1} << 40)}}, &damage),
            (std::vector<int64_t>{0, 0, 40'000, 60'000}));
  EXPECT_EQ(damage.wild_times, 1);
  EXPECT_EQ(read_times("bus_wild_first", 3, {{0, kT0 - (int64_t{1} << 45)}}, &damage),
            (std::vector<int64_t>{20'000, 20'000, 40'000}));
  EXPECT_EQ(damage.wild_times, 1);
}

TEST(LogFiles, AClockStepAndALoneMessageInAPauseAreNotDamage) {
  constexpr int64_t kT0 = 1'700'000'000'000'000;
  constexpr int64_t kHour = 3'600'000'000;
  LogReader::Damage damage;
  // Stepped an hour ahead at event 2, and back again at event 4.
  read_times("bus_step", 6, {{2, kT0 + kHour}, {3, kT0 + kHour + 20'000}}, &damage);
  EXPECT_FALSE(damage.damaged()) << damage.summary();
  // One message in the middle of a 60 s pause.
  read_times("bus_pause", 4, {{2, kT0 + 30'000'000}, {3, kT0 + 60'000'000}}, &damage);
  EXPECT_FALSE(damage.damaged()) << damage.summary();
}

TEST(LogFiles, EmptyLogHasNoEvents) {
  const std::string path = whiskeye::testing::scratch_file("bus_empty", ".lcmlog");
  write_bytes(path, {});
  auto [xs, damage] = read_all(path);
  EXPECT_TRUE(xs.empty());
  EXPECT_FALSE(damage.damaged());
}

TEST(LogFiles, ViewOwnerKeepsTheDataAfterTheReaderIsGone) {
  const std::string path = whiskeye::testing::scratch_file("bus_owner", ".lcmlog");
  three_event_log(path);
  LogReader::EventView ev;
  {
    LogReader in(path);
    ASSERT_TRUE(in.next(ev));
    ASSERT_TRUE(in.next(ev));
  }
  ASSERT_TRUE(ev.owner);
  pose2d_t p;
  ASSERT_TRUE(decode_message(ev.data, p));
  EXPECT_EQ(p.x, 1.0);
  EXPECT_EQ(ev.channel, "A");
}

// A log of `n` events on channels of 1–12 characters with 0 B to 300 kB of data (kStreamed maps what
// is 256 kB or more), 50 Hz apart, and the bytes LCM's writer gives it.
std::vector<uint8_t> random_log(const std::string& path, std::mt19937& rng, int n) {
  {
    LogWriterBus out(path);
    std::uniform_int_distribution<int> kind(0, 19), small(0, 60), medium(100, 5000), letter('A', 'Z');
    for (int i = 0; i < n; ++i) {
      out.set_time(1'700'000'000'000'000 + i * 20'000);
      std::string channel(static_cast<std::size_t>(1 + i % 12), 'X');
      for (char& c : channel) c = static_cast<char>(letter(rng));
      const int k = kind(rng);
      std::vector<uint8_t> data(
          static_cast<std::size_t>(k == 0 ? 300'000 : k == 1 ? 70'000 : k < 5 ? medium(rng) : small(rng)));
      for (uint8_t& b : data) b = static_cast<uint8_t>(rng());
      out.publish_raw(channel, data);
    }
  }
  std::ifstream f(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), {});
}

struct ReadBack {
  std::vector<std::tuple<int64_t, std::string, std::vector<uint8_t>>> events;
  LogReader::Damage damage;
  double progress = 0;
};
// `deferred`: the channel LogReader::defer() was given; its events' rest is read before their bytes are taken.
ReadBack read_back(LogReader& in, const std::string& deferred = "") {
  ReadBack r;
  LogReader::EventView ev;
  while (in.next(ev)) {
    if (!deferred.empty() && ev.channel == deferred) in.read_rest(ev.owner);
    r.events.emplace_back(ev.utime, std::string(ev.channel), std::vector<uint8_t>(ev.data.begin(), ev.data.end()));
  }
  r.damage = in.damage();
  r.progress = in.progress();
  return r;
}
void expect_same(const ReadBack& a, const ReadBack& b, const std::string& what) {
  EXPECT_EQ(a.events.size(), b.events.size()) << what;
  EXPECT_TRUE(a.events == b.events) << what;
  EXPECT_EQ(a.damage.first_problem, b.damage.first_problem) << what;
  EXPECT_EQ(a.damage.skipped_bytes, b.damage.skipped_bytes) << what;
  EXPECT_EQ(a.damage.damaged_places, b.damage.damaged_places) << what;
  EXPECT_EQ(a.damage.truncated_tail, b.damage.truncated_tail) << what;
  EXPECT_EQ(a.damage.wild_times, b.damage.wild_times) << what;
  EXPECT_EQ(a.progress, b.progress) << what;
}

// Reading the file in chunks (kStreamed) must see exactly what the whole file in memory shows, for
// any chunk size, on good logs and damaged ones: bytes flipped, sync words and junk inserted, event
// times gone wild, the tail cut off. Chunk sizes down to one byte put every boundary (inside a
// header, between an event and the next one's header, inside a sync word) on a chunk's edge.
TEST(LogFiles, StreamedReadingSeesWhatTheWholeFileShowsGoodOrDamaged) {
  const std::string path = whiskeye::testing::scratch_file("bus_streamed", ".lcmlog");
  std::mt19937 rng(27);
  int damaged = 0;
  for (int round = 0; round < 40; ++round) {
    std::vector<uint8_t> bytes = random_log(path, rng, 1 + round % 17);
    std::uniform_int_distribution<std::size_t> where(0, bytes.size() - 1);
    const uint8_t sync[4] = {0xED, 0xA1, 0xDA, 0x01};
    switch (round % 5) {
      case 0: break;  // undamaged
      case 1:
        for (int k = 0; k < 1 + round % 4; ++k) bytes[where(rng)] ^= static_cast<uint8_t>(1u << (rng() % 8));
        break;
      case 2: {
        std::vector<uint8_t> junk(static_cast<std::size_t>(rng() % 40));
        for (uint8_t& b : junk) b = static_cast<uint8_t>(rng());
        junk.insert(junk.begin() + static_cast<std::ptrdiff_t>(junk.size() / 2), sync, sync + 4);
        bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(where(rng)), junk.begin(), junk.end());
        break;
      }
      case 3: bytes[where(rng) / 28 * 28 % bytes.size()] = 0; bytes[std::min(bytes.size() - 1, std::size_t{15})] ^= 0x40; break;
      case 4: bytes.resize(where(rng)); break;
    }
    const std::string damaged_path = path + ".damaged";
    std::ofstream(damaged_path, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    LogReader whole(std::span<const uint8_t>(bytes), damaged_path);
    const ReadBack expected = read_back(whole);
    damaged += expected.damage.damaged();
    LogReader mapped(damaged_path, LogReader::Access::kMapped);
    expect_same(read_back(mapped), expected, "mapped, round " + std::to_string(round));
    for (std::size_t chunk : {std::size_t{1}, std::size_t{3}, std::size_t{28}, std::size_t{29}, std::size_t{100},
                              std::size_t{4096}, LogReader::kDefaultChunkBytes}) {
      LogReader streamed(damaged_path, LogReader::Access::kStreamed, chunk);
      expect_same(read_back(streamed), expected, "streamed in chunks of " + std::to_string(chunk) + ", round " +
                                                      std::to_string(round));
      // The same with the data of one channel's large events deferred (a replay's camera frames).
      const auto large = std::find_if(expected.events.begin(), expected.events.end(),
                                      [](const auto& e) { return std::get<2>(e).size() > 1000; });
      if (large != expected.events.end()) {
        const std::string channel = std::get<1>(*large);
        LogReader deferring(damaged_path, LogReader::Access::kStreamed, chunk);
        deferring.defer(channel, static_cast<std::size_t>(round % 3 == 0 ? 0 : round % 3 == 1 ? 10 : 44));
        expect_same(read_back(deferring, channel), expected, "deferring " + channel + ", chunks of " + std::to_string(chunk) +
                                                                 ", round " + std::to_string(round));
      }
    }
    std::filesystem::remove(damaged_path);
  }
  EXPECT_GE(damaged, 20) << "the rounds meant to damage the log did";
}

// A deferred event's data past its first bytes is read from the file when read_rest() asks, not
// before: bytes changed in the file in between are what the view then shows. Events of other
// channels, and the deferred channel's small ones, are read whole as they come.
TEST(LogFiles, ADeferredEventsRestIsReadOnlyWhenAskedFor) {
  const std::string path = whiskeye::testing::scratch_file("bus_deferred", ".lcmlog");
  {
    LogWriterBus out(path);
    out.set_time(1'700'000'000'000'000);
    out.publish_raw("SMALL", std::vector<uint8_t>(100, 1));
    out.publish_raw("CAMERA", std::vector<uint8_t>(600'000, 2));
    out.publish_raw("OTHER", std::vector<uint8_t>(300'000, 3));
    out.publish_raw("CAMERA", std::vector<uint8_t>(20, 4));
  }
  LogReader in(path, LogReader::Access::kStreamed, 4096);
  in.defer("CAMERA", 16);
  LogReader::EventView small, camera, other, tiny;
  ASSERT_TRUE(in.next(small));
  ASSERT_TRUE(in.next(camera));
  ASSERT_EQ(camera.channel, "CAMERA");
  ASSERT_EQ(camera.data.size(), 600'000u);
  const std::size_t data_at = 28 + 5 + 100 + 28 + 6;  // two event headers, "SMALL", its data, "CAMERA"
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(data_at));
    const std::vector<char> changed(600'000, 7);
    f.write(changed.data(), static_cast<std::streamsize>(changed.size()));
  }
  ASSERT_TRUE(in.next(other));
  ASSERT_TRUE(in.next(tiny));
  EXPECT_TRUE(std::all_of(other.data.begin(), other.data.end(), [](uint8_t b) { return b == 3; })) << "read whole";
  EXPECT_TRUE(std::all_of(tiny.data.begin(), tiny.data.end(), [](uint8_t b) { return b == 4; })) << "read whole";
  in.read_rest(other.owner);  // not deferred: nothing to do
  EXPECT_TRUE(std::all_of(camera.data.begin(), camera.data.begin() + 16, [](uint8_t b) { return b == 2; }))
      << "the first 16 bytes were read with the header";
  // A part first (the rows a crop uses): read now, from the file as it is then; the file then
  // changes again, and the rest is read as it is at the second request.
  in.read_rest(camera.owner, camera.data.first(200'000));
  EXPECT_TRUE(std::all_of(camera.data.begin() + 4096, camera.data.begin() + 200'000, [](uint8_t b) { return b == 7; }))
      << "the part asked for is read when asked for";
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(data_at));
    const std::vector<char> changed(600'000, 9);
    f.write(changed.data(), static_cast<std::streamsize>(changed.size()));
  }
  in.read_rest(camera.owner, camera.data.first(100'000));  // within what was read: nothing to do
  in.read_rest(camera.owner);
  EXPECT_TRUE(std::all_of(camera.data.begin() + 4096, camera.data.begin() + 200'000, [](uint8_t b) { return b == 7; }))
      << "bytes read are not read again";
  EXPECT_TRUE(std::all_of(camera.data.begin() + 200'000, camera.data.end(), [](uint8_t b) { return b == 9; }))
      << "the rest is read when asked for, from the file as it is then";
  in.read_rest(camera.owner);  // read already: nothing more happens
  EXPECT_EQ(camera.data[599'999], 9);
  EXPECT_FALSE(in.next(small));
  EXPECT_FALSE(in.damage().damaged());
  // A copied event (LogEvent) is always whole.
  LogReader copying(path, LogReader::Access::kStreamed, 4096);
  copying.defer("CAMERA", 16);
  LogEvent e;
  ASSERT_TRUE(copying.next(e));
  ASSERT_TRUE(copying.next(e));
  ASSERT_EQ(e.channel, "CAMERA");
  EXPECT_TRUE(std::all_of(e.data.begin() + 16, e.data.end(), [](uint8_t b) { return b == 9; }));
}

// A replay keeps a view's owner for as long as it needs the bytes (slamd keeps camera frames until a
// whisk cycle takes one): the bytes of a held view are never overwritten by reading on, though free
// chunks are reused. (That they are is a matter of speed: log-io-bench.)
TEST(LogFiles, StreamedViewsStayIntactWhileHeld) {
  const std::string path = whiskeye::testing::scratch_file("bus_streamed_owner", ".lcmlog");
  std::mt19937 rng(5);
  const std::vector<uint8_t> bytes = random_log(path, rng, 300);
  LogReader whole(std::span<const uint8_t>(bytes), path);
  const ReadBack expected = read_back(whole);
  LogReader in(path, LogReader::Access::kStreamed, 256);
  std::vector<LogReader::EventView> held;
  LogReader::EventView ev;
  while (in.next(ev)) held.push_back(ev);
  ASSERT_EQ(held.size(), expected.events.size());
  for (std::size_t i = 0; i < held.size(); ++i) {
    EXPECT_EQ(std::string(held[i].channel), std::get<1>(expected.events[i])) << i;
    EXPECT_TRUE(std::equal(held[i].data.begin(), held[i].data.end(), std::get<2>(expected.events[i]).begin(),
                           std::get<2>(expected.events[i]).end()))
        << "event " << i << "'s bytes changed while held";
  }
}

TEST(LogFiles, AStreamedLogThatGetsShorterWhileReadIsAnErrorNamingIt) {
  const std::string path = whiskeye::testing::scratch_file("bus_streamed_shrinks", ".lcmlog");
  std::mt19937 rng(9);
  random_log(path, rng, 200);
  LogReader in(path, LogReader::Access::kStreamed, 512);
  LogReader::EventView ev;
  ASSERT_TRUE(in.next(ev));
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
  try {
    while (in.next(ev)) {
    }
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": the LCM log got shorter while being read"), std::string::npos) << e.what();
  }
}

// Read syscalls of this process so far (/proc/self/io's syscr; pread counts).
long read_syscalls() {
  std::ifstream io("/proc/self/io");
  for (std::string key; io >> key;) {
    long v = 0;
    io >> v;
    if (key == "syscr:") return v;
  }
  return -1;
}

TEST(LogFiles, GarbageOfRepeatedSyncWordsIsSkippedReadingEachByteOnce) {
  const std::string path = whiskeye::testing::scratch_file("bus_sync_garbage", ".lcmlog");
  std::vector<char> bytes = three_event_log(path);
  // 1 MiB of sync words after the first event (69 bytes: 28 of header, "A", 40 of pose2d_t): every
  // one a candidate that fails (its channel length is the next sync word, negative). A header's
  // worth of zero bytes ends it, so that no candidate reads the next event's header as its lengths.
  constexpr std::size_t kGarbage = (1 << 20) + 28;
  constexpr std::size_t kFirstEvent = 28 + 1 + 8 + 4 * 8;
  std::vector<char> garbage(kGarbage, 0);
  for (std::size_t i = 0; i + 28 < kGarbage; i += 4) std::memcpy(&garbage[i], "\xED\xA1\xDA\x01", 4);
  bytes.insert(bytes.begin() + kFirstEvent, garbage.begin(), garbage.end());
  write_bytes(path, bytes);
  constexpr std::size_t kChunk = 64 * 1024;
  const long before = read_syscalls();
  ASSERT_GE(before, 0) << "no /proc/self/io";
  LogReader in(path, LogReader::Access::kStreamed, kChunk);
  LogReader::EventView ev;
  int events = 0;
  while (in.next(ev)) ++events;
  const long reads = read_syscalls() - before;
  EXPECT_EQ(events, 3);
  EXPECT_EQ(in.damage().skipped_bytes, kGarbage);
  EXPECT_EQ(in.damage().damaged_places, 1) << in.damage().summary();
  // Each byte read once: a pread per chunk (and a few for the chunk's remainder), not one per sync word
  // (262,144 before).
  EXPECT_LE(reads, static_cast<long>(2 * (bytes.size() / kChunk) + 16)) << "pread calls for " << bytes.size() << " bytes";
}

TEST(LogFiles, AFifoIsRefusedAsNotARegularFileWithoutWaitingForAWriter) {
  const std::string path = whiskeye::testing::scratch_file("bus_fifo", ".lcmlog");
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0) << std::strerror(errno);
  for (const LogReader::Access access : {LogReader::Access::kMapped, LogReader::Access::kStreamed}) {
    auto opening = std::async(std::launch::async, [&] {
      try {
        LogReader r(path, access);
        return std::string("opened");
      } catch (const std::runtime_error& e) {
        return std::string(e.what());
      }
    });
    if (opening.wait_for(std::chrono::seconds(20)) == std::future_status::timeout) {
      ADD_FAILURE() << "the reader waits for a writer to open the FIFO";
      const int w = ::open(path.c_str(), O_WRONLY);  // lets the blocked open() return, so the test ends
      ::close(w);
    }
    EXPECT_EQ(opening.get(), path + ": cannot open the LCM log for reading: not a regular file");
  }
}

TEST(LogFiles, AProcFileThatReportsNoBytesButHoldsSomeIsRefused) {
  for (const LogReader::Access access : {LogReader::Access::kMapped, LogReader::Access::kStreamed}) {
    try {
      LogReader r("/proc/self/status", access);
      ADD_FAILURE() << "read /proc/self/status as an empty log";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "/proc/self/status: cannot open the LCM log for reading: not a regular file (it reports 0 "
                             "bytes but holds data)");
    }
  }
}

TEST(LogFiles, MissingFileIsAnErrorNamingIt) {
  try {
    LogReader r("/nonexistent/x.lcmlog");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/x.lcmlog"), std::string::npos);
  }
}

}  // namespace
}  // namespace whiskeye
