// The transports of the seam (bus.h): in-memory, live LCM, an LCM log written; UDP drop counts.
#include "whiskeye/common/bus.h"
#include "whiskeye/common/log.h"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <cstdio>
#include <cstring>
#include <regex>

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
  publish_shared(channel, data, nullptr);
}

void MemoryBus::publish_shared(const std::string& channel, std::span<const uint8_t> data,
                               std::shared_ptr<const void> data_owner) {
  const MessageInfo info{channel, now_utime_, std::move(data_owner)};
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

// ---- UDP receive drops ----

int64_t udp_receive_drops(std::string_view text, const std::vector<uint64_t>& inodes) {
  int64_t drops = 0;
  std::size_t at = text.find('\n');  // after the header line
  while (at != std::string_view::npos && at + 1 < text.size()) {
    const std::size_t end = text.find('\n', at + 1);
    const std::string_view line = text.substr(at + 1, end == std::string_view::npos ? std::string_view::npos : end - at - 1);
    at = end;
    // sl local rem st tx:rx tr:when retrnsmt uid timeout inode ref pointer drops
    std::vector<std::string_view> fields;
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && line[i] == ' ') ++i;
      const std::size_t start = i;
      while (i < line.size() && line[i] != ' ') ++i;
      if (i > start) fields.push_back(line.substr(start, i - start));
    }
    if (fields.size() < 13) continue;
    uint64_t inode = 0;
    int64_t d = 0;
    std::from_chars(fields[9].data(), fields[9].data() + fields[9].size(), inode);
    std::from_chars(fields[12].data(), fields[12].data() + fields[12].size(), d);
    if (std::find(inodes.begin(), inodes.end(), inode) != inodes.end()) drops += d;
  }
  return drops;
}

int64_t udp_receive_drops() {
  std::vector<uint64_t> inodes;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    std::error_code link_ec;
    const std::string target = std::filesystem::read_symlink(entry.path(), link_ec).string();
    if (!link_ec && target.rfind("socket:[", 0) == 0) inodes.push_back(std::strtoull(target.c_str() + 8, nullptr, 10));
  }
  if (ec) return -1;
  int64_t drops = 0;
  bool read_any = false;
  for (const char* table : {"/proc/self/net/udp", "/proc/self/net/udp6"}) {
    std::ifstream in(table);
    if (!in) continue;
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    drops += udp_receive_drops(text, inodes);
    read_any = true;
  }
  return read_any ? drops : -1;
}

// ---- LcmBus ----

struct LcmBus::Adapter {
  std::string channel;
  RawHandler handler;
  lcm::Subscription* subscription = nullptr;
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const MessageInfo info{channel, rbuf->recv_utime, nullptr};
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
  errno = 0;
  if (lcm_->publish(channel, data.data(), static_cast<unsigned int>(data.size())) == 0) return;
  const int err = errno;
  const int64_t n = publish_errors_.fetch_add(1) + 1;
  int64_t power = 1;
  while (power * 10 <= n) power *= 10;
  if (n == power) {
    log_warning("LCM: cannot send on " + channel + " (" + std::to_string(data.size()) +
                " bytes): " + (err != 0 ? std::strerror(err) : "send failed") + "; " + std::to_string(n) +
                " message(s) dropped so far");
  }
}

void LcmBus::subscribe_raw(const std::string& channel, RawHandler handler) {
  adapters_.push_back(std::make_unique<Adapter>(Adapter{channel, std::move(handler), nullptr}));
  Adapter& adapter = *adapters_.back();
  adapter.subscription = lcm_->subscribe(channel, &Adapter::handle, &adapter);
  if (const auto it = queue_capacity_.find(channel); it != queue_capacity_.end() && adapter.subscription != nullptr) {
    adapter.subscription->setQueueCapacity(it->second);
  }
}

void LcmBus::set_queue_capacity(const std::string& channel, int messages) {
  if (messages < 0) throw std::invalid_argument("LcmBus::set_queue_capacity: negative capacity for " + channel);
  queue_capacity_[channel] = messages;
  for (const auto& adapter : adapters_) {
    if (adapter->channel == channel && adapter->subscription != nullptr) adapter->subscription->setQueueCapacity(messages);
  }
}

int LcmBus::handle_timeout(int timeout_ms) { return lcm_->handleTimeout(timeout_ms); }

int LcmBus::fileno() { return lcm_->getFileno(); }

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
