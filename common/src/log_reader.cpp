// LogReader (log_reader.h): an LCM log file read directly, mapped or streamed.
#include "whiskeye/common/log_reader.h"

#include "whiskeye/common/input_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace whiskeye {

// Where the log's bytes come from. view(at, len) makes bytes [at, at + len) of the file readable
// (len ≤ size() - at) and returns a pointer to byte `at`, valid until the next call; share(owner)
// makes `owner` keep the bytes of the last view alive (an event view's owner), reassigning it only
// when it holds something else.
class LogReader::Source {
 public:
  virtual ~Source() = default;
  std::size_t size() const { return size_; }
  virtual const uint8_t* view(std::size_t at, std::size_t len) = 0;
  virtual void share(std::shared_ptr<const void>& owner) const = 0;
  // How many bytes one view of a search for the next sync word covers (at least 4).
  virtual std::size_t search_window() const = 0;
  // How many bytes from `at` a view gives without reading (0: none of them are held).
  virtual std::size_t held(std::size_t at) const = 0;
  // Like view(at, len), but of those bytes only the first `ready` (≤ len) need be read now; the
  // rest is read by read_rest() of the view's owner. The view is shared into `owner` at once.
  virtual const uint8_t* view_deferred(std::size_t at, std::size_t len, std::size_t /*ready*/,
                                       std::shared_ptr<const void>& owner) {
    const uint8_t* v = view(at, len);
    share(owner);
    return v;
  }
  // Reads what a deferred view (`owner`'s) lacks up to `end` (one past the last byte wanted; nullptr:
  // the view's end).
  virtual void read_rest(const std::shared_ptr<const void>&, const uint8_t* /*end*/) {}

 protected:
  std::size_t size_ = 0;
};

namespace {

// The whole log file mapped read-only, or the caller's bytes; unmapped when the last owner lets go.
struct LogBytes {
  const uint8_t* bytes;
  std::size_t size;
  bool mapped;  // false: bytes the caller owns
  LogBytes(const uint8_t* b, std::size_t s, bool m) : bytes(b), size(s), mapped(m) {}
  LogBytes(const LogBytes&) = delete;
  LogBytes& operator=(const LogBytes&) = delete;
  ~LogBytes() {
    if (mapped && bytes != nullptr) ::munmap(const_cast<uint8_t*>(bytes), size);
  }
};

// The whole log in memory (mapped, or the caller's bytes): a view is a pointer into it.
class MemorySource final : public LogReader::Source {
 public:
  explicit MemorySource(std::shared_ptr<const LogBytes> log_bytes) : log_bytes_(std::move(log_bytes)) { size_ = log_bytes_->size; }
  const uint8_t* view(std::size_t at, std::size_t) override { return log_bytes_->bytes + at; }
  void share(std::shared_ptr<const void>& owner) const override {
    if (owner != log_bytes_) owner = log_bytes_;
  }
  std::size_t search_window() const override { return size_; }
  std::size_t held(std::size_t at) const override { return size_ - std::min(at, size_); }

 private:
  std::shared_ptr<const LogBytes> log_bytes_;
};

// The log read in file order with pread() into chunks: the current chunk holds the bytes of the last
// view; a new one starts at the view asked for and is filled up to its capacity, or to the end of a
// larger view (a camera frame gets a chunk of its own size). A chunk a view's owner still holds is
// never written again; free ones are reused, so a replay that keeps few views runs in a few warm
// chunks whatever the log's size. Every byte is copied, frames nobody reads too: on the development
// VM that costs less than mapping the pages (docs/performance.md, "### Replay").
class StreamSource final : public LogReader::Source {
 public:
  StreamSource(int fd, std::size_t size, std::size_t chunk_bytes, std::string path)
      : fd_(fd), chunk_bytes_(std::max<std::size_t>(chunk_bytes, 1)), path_(std::move(path)) {
    size_ = size;
  }
  ~StreamSource() override { ::close(fd_); }
  StreamSource(const StreamSource&) = delete;
  StreamSource& operator=(const StreamSource&) = delete;

  const uint8_t* view(std::size_t at, std::size_t len) override {
    if (current_ && held(at) >= len) return current_->bytes.get() + (at - current_->start);
    const std::size_t want = std::min(std::max(chunk_bytes_, len), size_ - at);
    start_chunk(at, want, want);
    return current_->bytes.get();
  }
  void share(std::shared_ptr<const void>& owner) const override {
    if (owner != current_) owner = current_;
  }
  const uint8_t* view_deferred(std::size_t at, std::size_t len, std::size_t ready,
                               std::shared_ptr<const void>& owner) override {
    if (held(at) < len) {
      // A chunk of the event's own, read up to `ready`.
      start_chunk(at, len, ready);
      std::erase_if(deferred_, [](const std::weak_ptr<Chunk>& d) { return d.expired(); });
      deferred_.push_back(current_);
    }
    share(owner);
    return current_->bytes.get() + (at - current_->start);
  }
  void read_rest(const std::shared_ptr<const void>& owner, const uint8_t* end) override {
    for (const std::weak_ptr<Chunk>& d : deferred_) {
      const std::shared_ptr<Chunk> c = d.lock();
      if (c && c.get() == owner.get()) {
        const uint8_t* begin = c->bytes.get();
        // Compared as addresses, so an `end` outside the chunk means its whole length, not UB.
        const auto at = reinterpret_cast<std::uintptr_t>(begin), to = reinterpret_cast<std::uintptr_t>(end);
        const std::size_t upto = end == nullptr || to < at || to - at > c->length ? c->length : to - at;
        if (c->filled < upto) fill(*c, upto);
        return;
      }
    }
  }
  std::size_t search_window() const override { return std::max<std::size_t>(chunk_bytes_, 8); }
  std::size_t held(std::size_t at) const override {
    if (!current_ || at < current_->start || at >= current_->start + current_->filled) return 0;
    return current_->start + current_->filled - at;
  }

 private:
  struct Chunk {
    std::unique_ptr<uint8_t[]> bytes;
    std::size_t capacity = 0;
    std::size_t start = 0;   // file offset of bytes[0]
    std::size_t filled = 0;  // bytes read
    std::size_t length = 0;  // bytes it stands for: more than `filled` while a deferred event's rest is unread
  };

  // Makes a chunk of `length` bytes from file offset `at` the current one, with its first `ready`
  // bytes (at least) read: the part the old current chunk holds is copied over (the rest of an event
  // whose end the old chunk lacks), the rest read from the file.
  void start_chunk(std::size_t at, std::size_t length, std::size_t ready) {
    std::shared_ptr<Chunk> next = take_free(length);
    next->start = at;
    next->filled = std::min(held(at), length);
    if (next->filled > 0) std::memcpy(next->bytes.get(), current_->bytes.get() + (at - current_->start), next->filled);
    fill(*next, ready);
    next->length = length;
    if (current_) keep_free(std::move(current_));
    current_ = std::move(next);
  }

  // Reads the chunk's bytes up to `upto` (from the file at its start).
  void fill(Chunk& c, std::size_t upto) {
    while (c.filled < upto) {
      const ssize_t got = ::pread(fd_, c.bytes.get() + c.filled, upto - c.filled, static_cast<off_t>(c.start + c.filled));
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) throw std::runtime_error(path_ + ": cannot read the LCM log: " + std::strerror(errno));
      if (got == 0) {
        throw std::runtime_error(path_ + ": the LCM log got shorter while being read (" + std::to_string(c.start + c.filled) +
                                 " of " + std::to_string(size_) + " bytes)");
      }
      c.filled += static_cast<std::size_t>(got);
    }
  }
  static constexpr std::size_t kKeptChunks = 16;  // chunks kept for reuse

  // A chunk of at least `bytes` nobody holds: a kept one, or a new one.
  std::shared_ptr<Chunk> take_free(std::size_t bytes) {
    for (auto it = kept_.begin(); it != kept_.end(); ++it) {
      if (it->use_count() == 1 && (*it)->capacity >= bytes) {
        std::shared_ptr<Chunk> c = std::move(*it);
        kept_.erase(it);
        return c;
      }
    }
    auto c = std::make_shared<Chunk>();
    c->capacity = std::max(bytes, chunk_bytes_);
    c->bytes = std::make_unique_for_overwrite<uint8_t[]>(c->capacity);
    return c;
  }
  // Keeps a chunk for reuse (once its views are gone). Beyond kKeptChunks, the oldest one still
  // held is let go (its holder frees it), else the oldest.
  void keep_free(std::shared_ptr<Chunk> c) {
    kept_.push_back(std::move(c));
    if (kept_.size() <= kKeptChunks) return;
    auto drop = std::find_if(kept_.begin(), kept_.end(), [](const auto& k) { return k.use_count() > 1; });
    kept_.erase(drop != kept_.end() ? drop : kept_.begin());
  }

  int fd_;
  std::size_t chunk_bytes_;
  std::string path_;
  std::shared_ptr<Chunk> current_;
  std::vector<std::shared_ptr<Chunk>> kept_;
  std::vector<std::weak_ptr<Chunk>> deferred_;  // chunks of deferred events, while a view holds them
};

using lcm_log::kEventHeaderBytes;
using lcm_log::kSyncWord;
constexpr int32_t kMaxLogChannelLength = 1000;  // what lcm-logger's reader accepts

// Checks that a plausible event starts at byte `at` of a file of `size` bytes, whose first
// min(kEventHeaderBytes, size - at) bytes are `h`: sync word, channel length in (0, 1000), data length
// ≥ 0, the whole event inside the file. `size` 0: implausible, then `truncated` says whether the
// file ends first, and `why` (if given) gets the reason; nothing is formatted for a good event.
struct EventCheck {
  std::size_t size = 0;
  bool truncated = false;
};
EventCheck check_event(const uint8_t* h, std::size_t size, std::size_t at, std::string* why) {
  const auto at_byte = [at] { return " at byte " + std::to_string(at); };
  if (size - at < kEventHeaderBytes) {
    if (why) *why = "truncated LCM log: incomplete event header" + at_byte() + " (file size " + std::to_string(size) + ")";
    return {0, true};
  }
  const lcm_log::EventHeader header = lcm_log::read_event_header(h);
  if (header.sync != kSyncWord) {
    if (why) *why = "corrupt LCM log: no event sync word" + at_byte();
    return {0, false};
  }
  const int32_t channel_len = header.channel_bytes;
  const int32_t data_len = header.data_bytes;
  if (channel_len <= 0 || channel_len >= kMaxLogChannelLength) {
    if (why) *why = "corrupt LCM log: channel length " + std::to_string(channel_len) + " in the event" + at_byte();
    return {0, false};
  }
  if (data_len < 0) {
    if (why) *why = "corrupt LCM log: data length " + std::to_string(data_len) + " in the event" + at_byte();
    return {0, false};
  }
  const std::size_t total = kEventHeaderBytes + static_cast<std::size_t>(channel_len) + static_cast<std::size_t>(data_len);
  if (size - at < total) {
    if (why) {
      *why = "truncated LCM log: the event" + at_byte() + " needs " + std::to_string(total) + " bytes, the file has " +
             std::to_string(size - at) + " left";
    }
    return {0, true};
  }
  return {total, false};
}

// The bytes of a header at `at` that the file has (fewer than a header at its end).
std::size_t header_bytes(std::size_t size, std::size_t at) { return std::min(kEventHeaderBytes, size - at); }

}  // namespace

LogReader::LogReader(const std::string& path, Access access, std::size_t chunk_bytes) : path_(path) {
  const InputFile file = open_input_file(path, "LCM log");
  const int fd = file.fd;
  const auto size = static_cast<std::size_t>(file.size);
  if (access == Access::kStreamed) {
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_SEQUENTIAL);
    source_ = std::make_unique<StreamSource>(fd, size, chunk_bytes, path);  // owns fd
    return;
  }
  const uint8_t* bytes = nullptr;
  if (size > 0) {
    void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p == MAP_FAILED) {
      const int err = errno;
      ::close(fd);
      throw std::runtime_error(path + ": cannot map the LCM log: " + std::strerror(err));
    }
    bytes = static_cast<const uint8_t*>(p);
    ::madvise(p, size, MADV_SEQUENTIAL);
  }
  ::close(fd);  // the mapping keeps the file
  source_ = std::make_unique<MemorySource>(std::make_shared<const LogBytes>(bytes, size, true));
}

LogReader::LogReader(std::span<const uint8_t> bytes, std::string name)
    : path_(std::move(name)), source_(std::make_unique<MemorySource>(std::make_shared<const LogBytes>(bytes.data(), bytes.size(), false))) {}

LogReader::~LogReader() = default;

bool LogReader::next(LogEvent& event) {
  EventView view;
  if (!next(view)) return false;
  if (!deferred_channel_.empty()) source_->read_rest(view.owner, nullptr);  // a copy is of the whole event
  event.utime = view.utime;
  event.channel.assign(view.channel);
  event.data.assign(view.data.begin(), view.data.end());
  return true;
}

bool LogReader::next(EventView& event) {
  Source& src = *source_;
  const std::size_t size = src.size();
  if (pos_ >= size) return false;
  std::string why;  // stays empty (no allocation) for a good event
  const EventCheck check = check_event(src.view(pos_, header_bytes(size, pos_)), size, pos_, &why);
  std::size_t total = check.size;
  if (total == 0) {
    // Damaged: note the first problem, then look for the next plausible event, as LCM's own reader
    // resynchronises on the sync word. Whatever cannot be read is skipped and counted.
    if (damage_.first_problem.empty()) damage_.first_problem = path_ + ": " + why;
    ++damage_.damaged_places;
    const uint8_t sync[4] = {kSyncWord >> 24, (kSyncWord >> 16) & 0xff, (kSyncWord >> 8) & 0xff, kSyncWord & 0xff};
    std::size_t at = pos_ + 1;
    for (;;) {
      // The next sync word, looked for a window at a time (a match across two windows is found in
      // the second, which starts 3 bytes before the first one's end). A search starts in the bytes
      // already read while they hold a header: garbage of sync words, each a failed candidate, is
      // then skipped in one read of every byte, not a window read again per candidate.
      std::size_t found = size;
      for (std::size_t from = at; from + sizeof sync <= size;) {
        const std::size_t held = src.held(from);
        const std::size_t len = held >= kEventHeaderBytes ? held : std::min(size - from, src.search_window());
        const uint8_t* w = src.view(from, len);
        if (const auto* hit = static_cast<const uint8_t*>(::memmem(w, len, sync, sizeof sync))) {
          found = from + static_cast<std::size_t>(hit - w);
          break;
        }
        from += len - (sizeof sync - 1);
      }
      if (found == size) {
        damage_.skipped_bytes += size - pos_;
        damage_.truncated_tail = check.truncated;
        pos_ = size;
        return false;
      }
      at = found;
      total = check_event(src.view(at, header_bytes(size, at)), size, at, nullptr).size;
      if (total != 0) break;
      ++at;
    }
    damage_.skipped_bytes += at - pos_;
    pos_ = at;
  }
  const std::size_t next_at = pos_ + total;
  const std::size_t next_header = next_at < size ? header_bytes(size, next_at) : 0;
  const lcm_log::EventHeader header = lcm_log::read_event_header(src.view(pos_, kEventHeaderBytes));
  const auto channel_len = static_cast<std::size_t>(header.channel_bytes);
  const auto data_len = static_cast<std::size_t>(header.data_bytes);
  const uint8_t* e = nullptr;  // the event, once it is shared into event.owner
  const uint8_t* next_h = nullptr;
  if (!deferred_channel_.empty() && data_len > read_first_ && src.held(pos_) < total) {
    // A large event not read yet: its header, channel and first data bytes now, the rest when its
    // channel is not the deferred one or read_rest() asks for it.
    e = src.view_deferred(pos_, total, kEventHeaderBytes + channel_len + read_first_, event.owner);
    if (std::string_view(reinterpret_cast<const char*>(e + kEventHeaderBytes), channel_len) != deferred_channel_) {
      src.read_rest(event.owner, nullptr);
    }
    if (next_header != 0) next_h = src.view(next_at, next_header);
  } else {
    // The event and the header after it in one view. The events ahead are only looked at, not
    // consumed.
    const uint8_t* h = src.view(pos_, total + next_header);
    if (next_header != 0) next_h = h + total;
  }
  event.utime = header.utime;
  // A time far from both neighbours while they agree with each other is a flipped bit: not a clock
  // step (the events after a step agree with it) nor a lone message in a pause (its neighbours do
  // not agree). The first and the last event have one neighbour: only a day off is damage there (the
  // first: from the next two, which agree).
  const auto distance = [](int64_t a, int64_t b) {
    return a > b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b) : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
  };
  const auto far = [&](int64_t a, int64_t b, int64_t limit) { return distance(a, b) > static_cast<uint64_t>(limit); };
  const std::size_t next_total = next_h != nullptr ? check_event(next_h, size, next_at, nullptr).size : 0;
  const bool has_next = next_total != 0;
  const int64_t next_utime = has_next ? lcm_log::read_event_header(next_h).utime : 0;
  bool wild = false;
  if (have_last_utime_ && has_next) {
    wild = !far(last_utime_, next_utime, kMaxTimeJumpUs) && far(event.utime, last_utime_, kMaxTimeJumpUs) &&
           far(event.utime, next_utime, kMaxTimeJumpUs);
  } else if (have_last_utime_) {
    wild = far(event.utime, last_utime_, kMaxEdgeTimeJumpUs);
  } else if (has_next) {
    // The first event: the next one stands for its time only if the one after it agrees.
    const std::size_t second_at = next_at + next_total;
    if (second_at < size) {
      const uint8_t* second = src.view(second_at, header_bytes(size, second_at));
      const bool has_second = check_event(second, size, second_at, nullptr).size != 0;
      wild = has_second && !far(next_utime, lcm_log::read_event_header(second).utime, kMaxTimeJumpUs) &&
             far(event.utime, next_utime, kMaxEdgeTimeJumpUs);
    }
  }
  if (wild) {
    const int64_t replacement = have_last_utime_ ? last_utime_ : next_utime;
    if (damage_.first_problem.empty()) {
      damage_.first_problem = path_ + ": corrupt LCM log: event time " + std::to_string(event.utime) + " us at byte " +
                              std::to_string(pos_) + " is out of line with the events around it (taken as " +
                              std::to_string(replacement) + " us)";
    }
    ++damage_.wild_times;
    event.utime = replacement;
  }
  last_utime_ = event.utime;
  have_last_utime_ = true;
  if (e == nullptr) {
    // Inside the view made above, unless the first event's look two ahead moved on (then read again).
    e = src.view(pos_, total);
    src.share(event.owner);
  }
  event.channel = std::string_view(reinterpret_cast<const char*>(e + kEventHeaderBytes), channel_len);
  event.data = std::span<const uint8_t>(e + kEventHeaderBytes + channel_len, data_len);
  pos_ += total;
  return true;
}

void LogReader::defer(std::string channel, std::size_t read_first) {
  deferred_channel_ = std::move(channel);
  read_first_ = read_first;
}

void LogReader::read_rest(const std::shared_ptr<const void>& owner) { source_->read_rest(owner, nullptr); }

void LogReader::read_rest(const std::shared_ptr<const void>& owner, std::span<const uint8_t> wanted) {
  source_->read_rest(owner, wanted.data() + wanted.size());
}

std::string LogReader::Damage::summary() const {
  if (!damaged()) return "";
  std::string s = first_problem;
  if (damaged_places > 0) {
    s += "; " + std::to_string(skipped_bytes) + " bytes skipped in " + std::to_string(damaged_places) +
         (damaged_places == 1 ? " place" : " places");
  }
  if (truncated_tail) s += ", the last event cut off";
  if (wild_times > 0) s += "; " + std::to_string(wild_times) + " event time(s) out of line with their neighbours replaced";
  return s;
}

double LogReader::progress() const {
  if (source_->size() == 0) return 0.0;
  return static_cast<double>(pos_) / static_cast<double>(source_->size());
}

}  // namespace whiskeye
