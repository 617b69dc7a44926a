#include "whiskeye/common/bus.h"

#include <lcm/lcm-cpp.hpp>

#include <regex>
#include <sys/stat.h>

namespace whiskeye {

void DecodeErrors::set_callback(Callback cb) {
  std::lock_guard<std::mutex> lock(mutex_);
  callback_ = std::move(cb);
}

void DecodeErrors::record(const std::string& channel, const std::string& reason) {
  total_.fetch_add(1);
  Callback cb;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++per_channel_[channel];
    cb = callback_;
  }
  if (cb) cb(channel, reason);
}

int64_t DecodeErrors::count(const std::string& channel) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = per_channel_.find(channel);
  return it == per_channel_.end() ? 0 : it->second;
}

// ---- MemoryBus ----

bool is_plain_channel_name(const std::string& channel) {
  return channel.find_first_of(".[]{}()\\*+?|^$") == std::string::npos;
}

struct MemoryBus::Sub {
  std::string name;  // exact name, when the pattern is not a regex (regex matching is slow)
  std::regex pattern;
  RawHandler handler;
  bool matches(const std::string& channel) const {
    return name.empty() ? std::regex_match(channel, pattern) : channel == name;
  }
};

void MemoryBus::publish_raw(const std::string& channel, std::span<const uint8_t> data) {
  const MessageInfo info{channel, now_utime_};
  // Copy: a handler may subscribe while we deliver.
  const auto subs = subs_;
  for (const auto& sub : subs) {
    if (sub->matches(channel)) sub->handler(data, info);
  }
}

void MemoryBus::subscribe_raw(const std::string& channel, RawHandler handler) {
  auto sub = std::make_shared<Sub>();
  if (is_plain_channel_name(channel)) {
    sub->name = channel;
  } else {
    sub->pattern = std::regex(channel, std::regex::extended);
  }
  sub->handler = std::move(handler);
  subs_.push_back(std::move(sub));
}

// ---- LcmBus ----

struct LcmBus::Adapter {
  RawHandler handler;
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const MessageInfo info{channel, rbuf->recv_utime};
    handler(std::span<const uint8_t>(static_cast<const uint8_t*>(rbuf->data), rbuf->data_size), info);
  }
};

LcmBus::LcmBus(const std::string& url) : lcm_(std::make_unique<lcm::LCM>(url)) {
  if (!lcm_->good()) {
    throw std::runtime_error("cannot start LCM on '" + (url.empty() ? std::string("default URL") : url) +
                             "' (for udpm:// a multicast route is needed: ip route add 224.0.0.0/4 dev lo)");
  }
}

LcmBus::~LcmBus() = default;

void LcmBus::publish_raw(const std::string& channel, std::span<const uint8_t> data) {
  if (lcm_->publish(channel, data.data(), static_cast<unsigned int>(data.size())) != 0) {
    throw std::runtime_error("LCM publish on " + channel + " failed");
  }
}

void LcmBus::subscribe_raw(const std::string& channel, RawHandler handler) {
  adapters_.push_back(std::make_unique<Adapter>(Adapter{std::move(handler)}));
  lcm_->subscribe(channel, &Adapter::handle, adapters_.back().get());
}

int LcmBus::handle_timeout(int timeout_ms) { return lcm_->handleTimeout(timeout_ms); }

int LcmBus::fileno() { return lcm_->getFileno(); }

// ---- LogReader ----

LogReader::LogReader(const std::string& path) : log_(std::make_unique<lcm::LogFile>(path, "r")) {
  if (!log_->good()) throw std::runtime_error(path + ": cannot open the LCM log for reading");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) size_ = st.st_size;
}

LogReader::~LogReader() = default;

bool LogReader::next(LogEvent& event) {
  const lcm::LogEvent* ev = log_->readNextEvent();
  if (ev == nullptr) return false;
  event.utime = ev->timestamp;
  event.channel = ev->channel;
  const auto* bytes = static_cast<const uint8_t*>(ev->data);
  event.data.assign(bytes, bytes + ev->datalen);
  return true;
}

bool LogReader::next(EventView& event) {
  const lcm::LogEvent* ev = log_->readNextEvent();
  if (ev == nullptr) return false;
  event.utime = ev->timestamp;
  event.channel = ev->channel;
  event.data = std::span<const uint8_t>(static_cast<const uint8_t*>(ev->data), static_cast<std::size_t>(ev->datalen));
  return true;
}

double LogReader::progress() const {
  if (size_ <= 0) return 0.0;
  const long pos = std::ftell(log_->getFilePtr());
  return pos < 0 ? 0.0 : static_cast<double>(pos) / static_cast<double>(size_);
}

// ---- LogWriterBus ----

LogWriterBus::LogWriterBus(const std::string& path) : log_(std::make_unique<lcm::LogFile>(path, "w")) {
  if (!log_->good()) throw std::runtime_error(path + ": cannot open the LCM log for writing");
}

LogWriterBus::~LogWriterBus() = default;

void LogWriterBus::set_time(int64_t utime) {
  now_utime_ = utime;
  local_.set_time(utime);
}

void LogWriterBus::publish_raw(const std::string& channel, std::span<const uint8_t> data) {
  lcm::LogEvent ev{};
  ev.eventnum = events_;
  ev.timestamp = now_utime_;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(data.size());
  ev.data = const_cast<uint8_t*>(data.data());  // LogFile::writeEvent does not modify it
  if (log_->writeEvent(&ev) != 0) throw std::runtime_error("cannot write to the LCM log");
  ++events_;
  local_.publish_raw(channel, data);
}

void LogWriterBus::subscribe_raw(const std::string& channel, RawHandler handler) {
  local_.subscribe_raw(channel, std::move(handler));
}

}  // namespace whiskeye
