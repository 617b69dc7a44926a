// Checkpoint blobs as an earlier format wrote them, made from today's by removing what was added
// since: the tests that a robot upgraded with its map resumes from it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace whiskeye::slam::testing {

// Where a map serialisation's links begin (after the experiences and the link count), and how many.
struct LinkSpan {
  std::size_t at = 0;
  uint64_t count = 0;
};
inline LinkSpan links_of(const std::vector<uint8_t>& map) {
  constexpr std::size_t kExperience = 7 * 8 + 8 + 3 * 4 + 1 + 4 + 1;
  uint64_t n = 0;
  LinkSpan span;
  std::memcpy(&n, map.data(), 8);
  std::memcpy(&span.count, map.data() + 8 + n * kExperience, 8);
  span.at = 8 + n * kExperience + 8;
  return span;
}

// `map` with each link cut to its first `keep` bytes of `stride`, and `drop_after_links` bytes
// removed at `drop_at` bytes after the links.
inline std::vector<uint8_t> cut_links(const std::vector<uint8_t>& map, std::size_t stride, std::size_t keep,
                                      std::size_t drop_at = 0, std::size_t drop_after_links = 0) {
  const LinkSpan links = links_of(map);
  std::vector<uint8_t> out(map.begin(), map.begin() + static_cast<std::ptrdiff_t>(links.at));
  std::size_t at = links.at;
  for (uint64_t l = 0; l < links.count; ++l, at += stride) {
    out.insert(out.end(), map.begin() + static_cast<std::ptrdiff_t>(at), map.begin() + static_cast<std::ptrdiff_t>(at + keep));
  }
  out.insert(out.end(), map.begin() + static_cast<std::ptrdiff_t>(at), map.begin() + static_cast<std::ptrdiff_t>(at + drop_at));
  out.insert(out.end(), map.begin() + static_cast<std::ptrdiff_t>(at + drop_at + drop_after_links), map.end());
  return out;
}

// An experience map's serialisation (format 7) as format 6 wrote it: without each link's gate (f64).
inline std::vector<uint8_t> map_as_format_6(const std::vector<uint8_t>& v7) {
  constexpr std::size_t kLink6 = 4 + 4 + 3 * 8 + 8 + 1 + 8;
  return cut_links(v7, kLink6 + 8, kLink6);
}

// The same (format 7) as formats 4 and 5 wrote it: also without each link's recognised ends (u8) and
// scale (f64), and the "current recognised" flag (u8) after the current experience (i32).
inline std::vector<uint8_t> map_as_format_5(const std::vector<uint8_t>& v7) {
  constexpr std::size_t kLink = 4 + 4 + 3 * 8 + 8;
  return cut_links(map_as_format_6(v7), kLink + 1 + 8, kLink, 4, 1);
}

}  // namespace whiskeye::slam::testing
