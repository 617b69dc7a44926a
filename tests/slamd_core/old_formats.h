// Checkpoint blobs as an earlier format wrote them, made from today's by removing what was added
// since: the tests that a robot upgraded with its map resumes from it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace whiskeye::slam::testing {

// An experience map's serialisation (format 6) as formats 4 and 5 wrote it: without each link's
// recognised ends (u8) and scale (f64), and the "current recognised" flag (u8) after the current
// experience.
inline std::vector<uint8_t> map_as_format_5(const std::vector<uint8_t>& v6) {
  constexpr std::size_t kExperience = 7 * 8 + 8 + 3 * 4 + 1 + 4 + 1;
  constexpr std::size_t kLink = 4 + 4 + 3 * 8 + 8;
  constexpr std::size_t kAddedPerLink = 1 + 8;
  uint64_t n = 0, nl = 0;
  std::memcpy(&n, v6.data(), 8);
  std::size_t at = 8 + n * kExperience;
  std::memcpy(&nl, v6.data() + at, 8);
  std::vector<uint8_t> out(v6.begin(), v6.begin() + static_cast<std::ptrdiff_t>(at + 8));
  at += 8;
  for (uint64_t l = 0; l < nl; ++l, at += kLink + kAddedPerLink) {
    out.insert(out.end(), v6.begin() + static_cast<std::ptrdiff_t>(at), v6.begin() + static_cast<std::ptrdiff_t>(at + kLink));
  }
  out.insert(out.end(), v6.begin() + static_cast<std::ptrdiff_t>(at), v6.begin() + static_cast<std::ptrdiff_t>(at + 4));
  out.insert(out.end(), v6.begin() + static_cast<std::ptrdiff_t>(at + 4 + 1), v6.end());
  return out;
}

}  // namespace whiskeye::slam::testing
