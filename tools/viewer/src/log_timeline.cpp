// A recorded log as a timeline (log_timeline.h).
#include "whiskeye/viewer/log_timeline.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"
#include "whiskeye/common/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <vector>

namespace whiskeye::viewer {

namespace {

// The name of a channel the viewer shows (static storage), or empty.
std::string_view shown(std::string_view channel) {
  for (const char* c : {channels::kVitaMap, channels::kVitaPose, channels::kVitaEvent, channels::kVitaMatch,
                        channels::kDriverStatus, channels::kSlamStatus, channels::kWhiskCycle, channels::kCamera}) {
    if (channel == c) return c;
  }
  return {};
}

using lcm_log::kEventHeaderBytes;

}  // namespace

struct LogTimeline::File {
  ~File() { ::close(fd); }
  int fd = -1;
  std::string path;
  struct stat indexed {};  // size and modification time when indexed
};

LogTimeline::LogTimeline(ViewerParams params) : params_(params), state_(params) {}
LogTimeline::~LogTimeline() = default;

void LogTimeline::add(int64_t utime, std::string_view channel, std::span<const uint8_t> data,
                      std::shared_ptr<const void> owner) {
  const std::string_view name = shown(channel);
  if (name.empty()) return;
  if (!events_.empty() && utime < events_.back().utime) sorted_ = false;
  events_.push_back({utime, name, data, std::move(owner)});
}

std::unique_ptr<LogTimeline> LogTimeline::from_file(const std::string& path, ViewerParams params) {
  auto timeline = std::make_unique<LogTimeline>(params);
  auto file = std::make_unique<File>();
  file->path = path;
  file->fd = open_input_file(path, "LCM log").fd;
  if (::fstat(file->fd, &file->indexed) != 0) {
    throw std::runtime_error(path + ": cannot open the LCM log for reading: " + std::strerror(errno));
  }
  // Read in order with pread() (a file that gets shorter meanwhile is an error, not a fault). The
  // reader skips damage and counts the bytes skipped, so each event's place follows from the last.
  LogReader reader(path, LogReader::Access::kStreamed);
  LogReader::EventView ev;
  uint64_t end = 0;
  std::size_t skipped = 0;
  while (reader.next(ev)) {
    const uint64_t at = end + (reader.damage().skipped_bytes - skipped);
    skipped = reader.damage().skipped_bytes;
    end = at + kEventHeaderBytes + ev.channel.size() + ev.data.size();
    const std::string_view name = shown(ev.channel);
    if (name.empty()) continue;
    if (!timeline->events_.empty() && ev.utime < timeline->events_.back().utime) timeline->sorted_ = false;
    timeline->events_.push_back({ev.utime, name, {}, nullptr, at, static_cast<uint32_t>(ev.data.size())});
  }
  timeline->damage_ = reader.damage().summary();
  timeline->file_ = std::move(file);
  timeline->sort();
  try {
    timeline->check_unchanged();
  } catch (const LogChanged&) {
    // Written to while it was read: served as an error until the viewer is restarted.
  }
  return timeline;
}

void LogTimeline::fail(const std::string& why) {
  if (changed_.empty()) changed_ = why + ": restart the viewer to see the log as it is now";
  state_ = ViewerState(params_);
  applied_ = 0;
  at_ = INT64_MIN;
  throw LogChanged(changed_);
}

void LogTimeline::check_unchanged() {
  if (!changed_.empty()) throw LogChanged(changed_);
  if (!file_) return;
  struct stat now {};
  if (::fstat(file_->fd, &now) != 0) fail(file_->path + ": cannot check the log: " + std::strerror(errno));
  const struct stat& was = file_->indexed;
  if (now.st_size < was.st_size) {
    fail(file_->path + " got shorter under the viewer (" + std::to_string(was.st_size) + " bytes when read, " +
         std::to_string(now.st_size) + " now)");
  }
  if (now.st_size != was.st_size || now.st_mtim.tv_sec != was.st_mtim.tv_sec || now.st_mtim.tv_nsec != was.st_mtim.tv_nsec) {
    fail(file_->path + " changed under the viewer since it was read");
  }
}

// Applies one event; an event in the file is read again, and must be the event that was indexed.
void LogTimeline::apply(const Event& e) {
  if (!e.owner && file_) {
    const std::size_t total = kEventHeaderBytes + e.channel.size() + e.size;
    auto bytes = std::make_shared<std::vector<uint8_t>>(total);
    std::size_t got = 0;
    while (got < total) {
      const ssize_t n = ::pread(file_->fd, bytes->data() + got, total - got, static_cast<off_t>(e.offset + got));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) fail(file_->path + ": cannot read the log: " + std::strerror(errno));
      if (n == 0) fail(file_->path + " got shorter under the viewer (it ends before byte " + std::to_string(e.offset + total) + ")");
      got += static_cast<std::size_t>(n);
    }
    const uint8_t* h = bytes->data();
    const lcm_log::EventHeader header = lcm_log::read_event_header(h);
    const bool same = header.sync == lcm_log::kSyncWord && header.channel_bytes == static_cast<int32_t>(e.channel.size()) &&
                      header.data_bytes == static_cast<int32_t>(e.size) &&
                      std::memcmp(h + kEventHeaderBytes, e.channel.data(), e.channel.size()) == 0;
    if (!same) fail(file_->path + " changed under the viewer (byte " + std::to_string(e.offset) + " no longer starts the event read there)");
    state_.apply(e.channel, e.utime, std::span<const uint8_t>(h + kEventHeaderBytes + e.channel.size(), e.size), bytes);
    return;
  }
  state_.apply(e.channel, e.utime, e.data, e.owner);
}

void LogTimeline::sort() {
  if (sorted_) return;
  std::stable_sort(events_.begin(), events_.end(), [](const Event& a, const Event& b) { return a.utime < b.utime; });
  sorted_ = true;
}

int64_t LogTimeline::start_utime() const { return events_.empty() ? 0 : std::min_element(events_.begin(), events_.end(), [](const Event& a, const Event& b) { return a.utime < b.utime; })->utime; }

int64_t LogTimeline::end_utime() const { return events_.empty() ? 0 : std::max_element(events_.begin(), events_.end(), [](const Event& a, const Event& b) { return a.utime < b.utime; })->utime; }

const ViewerState& LogTimeline::seek(int64_t t) {
  check_unchanged();
  sort();
  if (t < at_) {
    state_ = ViewerState(params_);
    applied_ = 0;
  }
  at_ = t;
  const auto end = static_cast<std::size_t>(
      std::upper_bound(events_.begin(), events_.end(), t, [](int64_t v, const Event& e) { return v < e.utime; }) -
      events_.begin());
  // The newest event of each latest-only channel in the range is applied last, in log order; the
  // ones before it are only counted (each replaces everything before it).
  std::map<std::string_view, std::size_t> newest;
  for (std::size_t i = applied_; i < end; ++i) {
    if (is_latest_only(events_[i].channel)) newest[events_[i].channel] = i;
  }
  std::vector<std::size_t> last;
  for (const auto& [channel, i] : newest) last.push_back(i);
  std::sort(last.begin(), last.end());
  for (std::size_t i = applied_; i < end; ++i) {
    const Event& e = events_[i];
    if (!is_latest_only(e.channel)) {
      apply(e);
    } else if (!std::binary_search(last.begin(), last.end(), i)) {
      state_.skip(e.channel, e.utime);
    }
  }
  for (std::size_t i : last) apply(events_[i]);
  applied_ = std::max(applied_, end);
  state_.set_now(t);
  return state_;
}

}  // namespace whiskeye::viewer
