// Fuzz target: based's parser of the Robotino's odometry reply (GET /data/odometry), the body of
// an HTTP reply from the network. Seeds: fuzz/corpus/odometry_reply.
#include "whiskeye/based/protocol.h"

#include <cmath>
#include <cstdlib>
#include <string_view>

using namespace whiskeye::based;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view body(reinterpret_cast<const char*>(data), size);
  OdometrySample s;
  std::string error;
  const bool ok = parse_odometry_reply(body, s, error);
  if (ok != error.empty()) std::abort();  // a failure says why, a success says nothing
  if (ok && !(std::isfinite(s.x) && std::isfinite(s.y) && std::isfinite(s.theta) && std::isfinite(s.vx) &&
              std::isfinite(s.vy) && std::isfinite(s.omega))) {
    std::abort();
  }
  return 0;
}
