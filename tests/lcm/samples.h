// One filled-in message of every LCM type of the project, for round-trip tests through real LCM
// tools. Each sample knows its encoded bytes and how to check that received bytes decode to it.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace whiskeye::testing {

struct TypeSample {
  std::string type;     // e.g. "pose2d_t"
  std::string channel;  // "TEST_pose2d_t"
  std::vector<uint8_t> bytes;
  // Decodes `data` as the type and re-encodes it: true iff that reproduces `bytes` exactly.
  std::function<bool(std::span<const uint8_t> data)> round_trips;
};

std::vector<TypeSample> all_type_samples();

}  // namespace whiskeye::testing
