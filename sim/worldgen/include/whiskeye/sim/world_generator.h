// World generator of vita-sim: draws a world of the paper's kind (a square arena with look-alike
// wall landmarks and feel-alike tactile landmarks, the robot circling inside) from a seed, and checks
// the draw with the aliasing check (alias_check.h); family `aliased` keeps its premise.
// A draw that fails is redrawn (a new draw from the same seed's stream), so a seed gives one world.
// Family `stress` draws an `aliased` world and then breaks the premise at one look-alike pair (no
// touch at either place). The result is the world's YAML (the format of docs/simulator.md) with a
// header saying how it was drawn and what was found. Pure: no files, no clocks.
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/sim/alias_check.h"
#include "whiskeye/sim/world.h"

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace whiskeye::sim {

// A bad generator option (unknown family, empty range); the message names the option.
class GeneratorOptionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct Range {
  double min = 0.0;
  double max = 0.0;
};

// The most kidnaps --kidnaps draws into one world.
inline constexpr int kMaxKidnaps = 20;

struct GeneratorOptions {
  uint64_t world_seed = 1;
  std::string family = "aliased";  // aliased | stress
  bool faults = false;             // add the standard sensor-fault set (see docs/simulator.md)
  int kidnaps = 0;                 // kidnaps drawn after the first lap (docs/simulator.md), 0..kMaxKidnaps
  Range side{5.0, 8.0};            // m, square arena side
  Range wall_landmarks{4, 8};
  Range tactile_landmarks{3, 6};
  Range radius{0.8, 1.3};          // m, trajectory radius (base origin)
  Range speed{0.07, 0.15};         // m/s, tangential
  Range laps{4, 10};
  Range odometry_bias_scale{0.5, 3.0};   // × the default world's biases
  Range odometry_noise_scale{1.0, 2.0};  // × the default world's noise
  Range camera_noise{2.0, 6.0};          // grey levels
  double lighting_change_probability = 0.5;
  int max_attempts = 200;
};

// Throws GeneratorOptionError naming the first bad option (its CLI name).
void validate(const GeneratorOptions& options);

struct GeneratedWorld {
  std::string yaml;  // header comment + `world:` document
  // The header's lines and the drawn parameters as JSON, numbers as the YAML writes them
  // (vita-sim --output-world-json), so a reader needs no YAML parser.
  std::string json;
  World world;       // the same, as loaded back
  AliasReport report;
  int attempts = 0;  // draws made (the last one kept)
  std::map<std::string, int> rejected;  // why the earlier draws failed the check, and how often
};

// Throws GeneratorOptionError for bad options and std::runtime_error when no draw passes the check
// within options.max_attempts.
GeneratedWorld generate_world(const GeneratorOptions& options, const RobotGeometry& robot,
                              const AliasCheckParams& check);

}  // namespace whiskeye::sim
