// Wrong loop closures added on purpose. See wrong_closures.h.
#include "whiskeye/slam/wrong_closures.h"

#include "counters.h"
#include "whiskeye/slam/experience_map.h"

#include <cmath>
#include <limits>

namespace whiskeye::slam {

std::optional<WrongClosureKind> wrong_closure_kind(const std::string& name) {
  for (const WrongClosureKind k : {WrongClosureKind::Random, WrongClosureKind::Local, WrongClosureKind::Group}) {
    if (name == to_string(k)) return k;
  }
  return std::nullopt;
}

const char* to_string(WrongClosureKind kind) {
  switch (kind) {
    case WrongClosureKind::Random: return "random";
    case WrongClosureKind::Local: return "local";
    case WrongClosureKind::Group: return "group";
  }
  return "random";
}

WrongClosures::WrongClosures(const WrongClosureParams& params) : params_(params), rng_(params.seed) {}

int WrongClosures::draw(const ExperienceMap& map, double min_m, double max_m) {
  const int n = map.size();
  if (n < 2) return -1;
  const Pose2 here = map.current_pose();
  std::uniform_int_distribution<int> pick(0, n - 1);
  for (int attempt = 0; attempt < 64; ++attempt) {
    const int id = pick(rng_);
    const Experience& e = map.experiences()[static_cast<size_t>(id)];
    const double d = std::hypot(e.pose.x - here.x, e.pose.y - here.y);
    if (id != map.current_id() && !e.retired && d >= min_m && d <= max_m) return id;
  }
  return -1;
}

int WrongClosures::on_cycle(const Event& event, ExperienceMap& map, int64_t utime) {
  const bool closure = event.type == EventType::Relocalise && event.to_id >= 0 && event.to_id != event.from_id;
  if (closure) count(closures_);
  bool linked = false;
  if (params_.kind == WrongClosureKind::Group) {
    if (closure && group_left_ == 0 && (closures_ - 1) % params_.group_size == 0) {
      group_target_ = draw(map, params_.far_m, std::numeric_limits<double>::infinity());
      group_left_ = group_target_ >= 0 ? params_.group_size : 0;
    }
    if (group_left_ > 0) {
      // The group walks along the experiences made after its first target (an earlier pass elsewhere,
      // made in order), one per cycle, so that its links agree with each other.
      while (group_target_ < map.size() && (map.experiences()[static_cast<size_t>(group_target_)].retired ||
                                            group_target_ == map.current_id())) {
        ++group_target_;
      }
      if (group_target_ < map.size()) linked = map.link_current_to(group_target_++, utime);
      --group_left_;
    }
  } else if (closure) {
    const bool local = params_.kind == WrongClosureKind::Local;
    // A target already linked to the robot's experience is drawn again (a link is made once).
    for (int attempt = 0; attempt < 16 && !linked; ++attempt) {
      const int target = local ? draw(map, params_.local_min_m, params_.local_max_m)
                               : draw(map, params_.far_m, std::numeric_limits<double>::infinity());
      if (target < 0) break;
      linked = map.link_current_to(target, utime);
    }
  }
  if (!linked) return 0;
  count(added_);
  return 1;
}

}  // namespace whiskeye::slam
