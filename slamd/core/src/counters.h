// The SLAM's event counters (cycles, refused inputs, localisations): counted up and never past the
// largest int64, so that a counter restored from a checkpoint at its end stays there instead of
// wrapping to a negative value the checkpoint loader refuses (a map that then cannot be loaded).
#pragma once

#include <cstdint>
#include <limits>

namespace whiskeye::slam {

inline void count(int64_t& counter) {
  if (counter < std::numeric_limits<int64_t>::max()) ++counter;
}

}  // namespace whiskeye::slam
