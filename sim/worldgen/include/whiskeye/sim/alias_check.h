// The aliasing check of a world, with the machinery the SLAM and the simulator use:
//   - visual aliasing: the noise-free view is rendered at every few degrees of the path, turned into
//     slamd's own visual template, and every pair of places at least `min_separation_m` apart is
//     compared with the matcher's own distance (column shifts included); a pair whose distance is
//     within the SLAM's visual match threshold (times a safety margin) looks alike;
//   - touch: at each place the whiskers are swept against the world with the simulator's contact
//     geometry; two tactile landmarks feel alike when every whisker's first-touch angle agrees along
//     the passage (within a tolerance);
//   - the premise: two places that look alike are told apart by touch (the sets of feel-alike
//     classes touched there differ), at least two look-alike pairs exist, and at least two
//     landmarks that feel alike stand where the views differ.
// Pure: no files, no clocks.
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/rcp/params.h"
#include "whiskeye/sim/world.h"
#include "whiskeye/slam/template_store.h"
#include "whiskeye/slam/visual_template.h"

#include <string>
#include <utility>
#include <vector>

namespace whiskeye::sim {

// What the check measures, from slamd's configuration (the matcher sees what slamd would).
struct AliasCheckParams {
  // slamd's visual template and matching (config/slam.yaml `slam.visual`, `slam.match`): a raw
  // visual distance within match.threshold_visual · match.sigma_visual is what slamd calls a match.
  slam::VisualParams visual;
  slam::MatchParams match;
  // The whisking controller's pattern (config/rcp.yaml `pattern`): a place's touch reaches half a
  // whisk cycle's travel either side of it.
  rcp::PatternParams whisking;
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

}  // namespace whiskeye::sim
