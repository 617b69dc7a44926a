// Test peer process for the LCM tool tests: publishes or receives one sample of every type.
//   lcm_peer receive [--timeout S]   prints READY once subscribed, OK <type> per verified type;
//                                    exit 0 once every type arrived intact, 1 on corruption/timeout
//   lcm_peer publish [--count N] [--interval-ms M]
//   lcm_peer write-bytes DIR          writes DIR/<type>.bin (encoded bytes) for other-language checks
#include "samples.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/clock.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <thread>

using whiskeye::testing::all_type_samples;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: lcm_peer receive|publish|write-bytes ...\n");
    return 2;
  }
  const std::string mode = argv[1];
  double timeout_s = 10.0;
  int count = 1;
  int interval_ms = 20;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--timeout") timeout_s = std::stod(argv[i + 1]);
    if (a == "--count") count = std::stoi(argv[i + 1]);
    if (a == "--interval-ms") interval_ms = std::stoi(argv[i + 1]);
  }
  const auto samples = all_type_samples();

  if (mode == "write-bytes") {
    if (argc < 3) return 2;
    for (const auto& s : samples) {
      std::ofstream out(std::string(argv[2]) + "/" + s.type + ".bin", std::ios::binary);
      out.write(reinterpret_cast<const char*>(s.bytes.data()), static_cast<std::streamsize>(s.bytes.size()));
    }
    return 0;
  }

  whiskeye::LcmBus bus;
  if (mode == "publish") {
    for (int n = 0; n < count; ++n) {
      for (const auto& s : samples) bus.publish_raw(s.channel, s.bytes);
      std::this_thread::sleep_for(std::chrono::milliseconds(interval_ms));
    }
    return 0;
  }
  if (mode != "receive") return 2;

  std::map<std::string, const whiskeye::testing::TypeSample*> by_channel;
  for (const auto& s : samples) by_channel[s.channel] = &s;
  std::set<std::string> verified;
  bool corrupt = false;
  bus.subscribe_raw("TEST_.*", [&](std::span<const uint8_t> data, const whiskeye::MessageInfo& info) {
    const auto it = by_channel.find(info.channel);
    if (it == by_channel.end()) return;
    if (!it->second->round_trips(data)) {
      std::printf("BAD %s\n", it->second->type.c_str());
      corrupt = true;
    } else if (verified.insert(it->second->type).second) {
      std::printf("OK %s\n", it->second->type.c_str());
    }
    std::fflush(stdout);
  });
  std::printf("READY\n");
  std::fflush(stdout);
  const int64_t deadline = whiskeye::monotonic_us() + static_cast<int64_t>(timeout_s * 1e6);
  while (!corrupt && verified.size() < samples.size() && whiskeye::monotonic_us() < deadline) {
    bus.handle_timeout(50);
  }
  for (const auto& s : samples) {
    if (!verified.count(s.type)) std::printf("MISSING %s\n", s.type.c_str());
  }
  return (!corrupt && verified.size() == samples.size()) ? 0 : 1;
}
