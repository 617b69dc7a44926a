// World generator of vita-sim: draws a world of the paper's kind (a square arena with look-alike
// wall landmarks and feel-alike tactile landmarks, the robot circling inside) from a seed, and checks
// the draw with the same machinery the SLAM and the simulator use:
//   - visual aliasing: the noise-free view is rendered at every few degrees of the path, turned into
//     slamd's own visual template, and every pair of places at least `min_separation_m` apart is
//     compared with the matcher's own distance (column shifts included); a pair whose distance is
//     within the SLAM's visual match threshold (times a safety margin) looks alike;
//   - touch: at each place the whiskers are swept against the world with the simulator's contact
//     geometry; two tactile landmarks feel alike when every whisker's first-touch angle agrees along
//     the passage (within a tolerance);
//   - the premise (family `aliased`): two places that look alike are told apart by touch (the sets of
//     feel-alike classes touched there differ), at least two look-alike pairs exist, and at least two
//     landmarks that feel alike stand where the views differ.
// A draw that fails is redrawn (a new draw from the same seed's stream), so a seed gives one world.
// Family `stress` draws an `aliased` world and then breaks the premise at one look-alike pair (no
// touch at either place). The result is the world's YAML (the format of docs/simulator.md) with a
// header saying how it was drawn and what was found. Pure: no files, no clocks.
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/sim/world.h"
#include "whiskeye/slam/template_store.h"
#include "whiskeye/slam/visual_template.h"

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

// What the check measures, from slamd's configuration (the matcher sees what slamd would).
struct AliasCheckParams {
  // slamd's visual template and matching (config/slam.yaml `slam.visual`, `slam.match`): a raw
  // visual distance within match.threshold_visual · match.sigma_visual is what slamd calls a match.
  slam::VisualParams visual;
  slam::MatchParams match;
  // A pair looks alike when its distance is within margin × the match distance: the check runs on
  // noise-free views, and camera noise and lighting only add to what slamd sees.
  double margin = 1.5;
  double angle_step_deg = 2.0;      // views rendered every this many degrees of the path
  double min_separation_m = 0.6;    // along the head's path: closer places are the same place
  double max_place_m = 1.0;         // a longer look-alike stretch is cut into places this long
  double feel_alike_tolerance_rad = 0.01;  // mean |Δ first-touch angle| of two alike landmarks
};

struct LookAlikePair {
  double angle_a_deg = 0.0;  // polar angles of the trajectory
  double angle_b_deg = 0.0;
  double distance = 0.0;     // the matcher's visual distance (mean |Δ| of the templates, 0..1)
};

// A stretch of the path whose view looks like another stretch's, with what is touched along it.
struct AliasedPlace {
  double from_deg = 0.0;  // polar angles, counter-clockwise from from_deg to to_deg
  double to_deg = 0.0;
  std::vector<std::string> touched;  // feel-alike classes of the landmarks touched there (sorted)
};

struct AliasReport {
  std::vector<LookAlikePair> pairs;        // the most alike pair of every two aliased places
  std::vector<AliasedPlace> places;
  std::vector<std::pair<int, int>> place_pairs;  // indices into places: those two look alike
  std::vector<std::pair<int, int>> untold_pairs; // of place_pairs: the touch does not differ
  // Stretches whose views are alike with the same stretch's further along (a blank wall seen from
  // places 0.6 m apart): not a pair of places but one place where only odometry tells where the
  // robot is; indices into places, like place_pairs, and not counted there.
  std::vector<std::pair<int, int>> featureless;
  // Feel-alike classes: solids' names grouped; the pairs of them standing where the views differ.
  std::vector<std::vector<std::string>> feel_alike_classes;
  std::vector<std::pair<std::string, std::string>> feel_alike_pairs_apart;
  bool premise_holds() const { return untold_pairs.empty() && place_pairs.size() >= 2 && !feel_alike_pairs_apart.empty(); }
};

// Measures a world's aliasing (renders and sweeps; ≈ 1 s for a full lap at 2° steps).
AliasReport check_aliasing(const World& world, const RobotGeometry& robot, const AliasCheckParams& params);

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
