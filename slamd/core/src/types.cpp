// Names of the core's enums (for YAML, logs and messages).
#include "whiskeye/slam/types.h"

namespace whiskeye::slam {

Mode parse_mode(const std::string& text) {
  if (text == "visual") return Mode::Visual;
  if (text == "tactile") return Mode::Tactile;
  if (text == "vita") return Mode::Vita;
  throw std::invalid_argument("unknown SLAM mode \"" + text + "\" (visual, tactile or vita)");
}

std::string to_string(Mode mode) {
  switch (mode) {
    case Mode::Visual: return "visual";
    case Mode::Tactile: return "tactile";
    case Mode::Vita: return "vita";
  }
  return "?";
}

std::string to_string(EventType type) {
  switch (type) {
    case EventType::SameExperience: return "same";
    case EventType::NewExperience: return "new";
    case EventType::Relocalise: return "relocalise";
  }
  return "?";
}

}  // namespace whiskeye::slam
