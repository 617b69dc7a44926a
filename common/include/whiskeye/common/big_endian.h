// Big-endian integers, as LCM writes them in its messages and its log files. Pure.
#pragma once

#include <cstdint>

namespace whiskeye {

inline int64_t read_be_i64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return static_cast<int64_t>(v);
}

inline int32_t read_be_i32(const uint8_t* p) {
  return static_cast<int32_t>((uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3]);
}

}  // namespace whiskeye
