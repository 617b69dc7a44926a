// Wrong loop closures added on purpose, as the robust back-end literature tests a back end
// (Sünderhauf & Protzel, IROS 2012): for every closure the front end makes, one more link that claims
// the robot is at an experience it is not at — drawn at random far away, locally (near, but beyond a
// neighbour's distance), or in groups of consecutive cycles onto consecutive experiences of an
// earlier pass elsewhere (mutually consistent, the hardest for a robust back end). The links enter
// the map as a false re-localisation's link would (a recognised end, robust), but the front end's
// state is left alone: the robot does not jump, so what is measured is what the back end makes of
// them. A test and study instrument (slamd --replay --inject-wrong-closures), never on in a live
// daemon. Pure: a seeded generator, no I/O.
#pragma once

#include "whiskeye/slam/types.h"

#include <cstdint>
#include <optional>
#include <random>
#include <string>

namespace whiskeye::slam {

class ExperienceMap;

enum class WrongClosureKind : uint8_t { Random, Local, Group };
// "random", "local", "group"; nullopt for anything else.
std::optional<WrongClosureKind> wrong_closure_kind(const std::string& name);
const char* to_string(WrongClosureKind kind);

struct WrongClosureParams {
  WrongClosureKind kind = WrongClosureKind::Random;
  uint64_t seed = 1;
  int group_size = 5;           // Group: consecutive cycles, one wrong link each, per group
  double far_m = 1.0;           // Random, Group: the target at least this far (map) from the robot
  double local_min_m = 0.5;     // Local: the target this far from the robot ...
  double local_max_m = 1.5;     // ... to this
};

class WrongClosures {
 public:
  explicit WrongClosures(const WrongClosureParams& params);

  // After a cycle's action rule while tracking: `event` is what the map did. A re-localisation onto
  // another experience (a closure) adds one wrong link (Random, Local) or, every group_size-th,
  // starts a group whose links are added on this and the next cycles. Returns the links added (0 or 1).
  int on_cycle(const Event& event, ExperienceMap& map, int64_t utime);
  int64_t added() const { return added_; }
  const WrongClosureParams& params() const { return params_; }

 private:
  // An experience whose map distance from the robot is in [min_m, max_m] (not retired, not the
  // current one), or -1 if a few draws find none.
  int draw(const ExperienceMap& map, double min_m, double max_m);

  WrongClosureParams params_;
  std::mt19937_64 rng_;
  int64_t closures_ = 0;     // the front end's closures seen
  int group_left_ = 0;       // links of the current group still to add
  int group_target_ = -1;    // the experience the group's next link goes to
  int64_t added_ = 0;
};

}  // namespace whiskeye::slam
