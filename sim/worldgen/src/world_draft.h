// The drafting of a generated world (private to whiskeye_worldgen): what the generator draws (the
// arena, its wall landmarks copied onto other walls for look-alike places, the tactile landmarks
// placed to tell those places apart, the trajectory and noise, the faults and kidnaps), and the
// draft written as a world file through WorldWriter.
#pragma once

#include "path_views.h"
#include "world_rng.h"

#include "whiskeye/sim/world_generator.h"
#include "whiskeye/sim/world_writer.h"

#include <string>
#include <utility>
#include <vector>

namespace whiskeye::sim::worldgen {

// Tactile landmark shapes, in the shape frame: x radially outwards from the path, y along it, the
// face nearest the path at x = 0.
struct ObjectShape {
  const char* name;
  bool circle;
  double radius;  // circle
  std::vector<std::pair<double, double>> points;
};

const std::vector<ObjectShape>& object_library();

// The near face of a tactile landmark is drawn 0.08-0.10 m outside the head's path.
inline constexpr double kMinGap = 0.08, kMaxGap = 0.10;

struct PatternSpec {
  std::string name;
  WorldWriter::Entry fields;  // the pattern's fields after its name
};

struct LandmarkSpec {
  int wall = 0;        // 0 east, 1 north, 2 west, 3 south (outward normal at 90°·wall)
  int slot = 0;        // offset from the wall's normal: kSlotDeg[slot]
  double width = 1.0;  // m
  double z0 = 0.25;
  double z1 = 1.05;
  int pattern = 0;
  std::string name;
};

inline constexpr double kSlotDeg[3] = {-28.0, 0.0, 28.0};

struct ObjectSpec {
  int shape = 0;        // index into object_library()
  double angle_deg = 0;  // polar angle of the path where it stands
  std::string name;
};

// The faults as drawn, each number at the decimals the file gives it.
struct FaultSpec {
  std::vector<int> dead_whiskers;
  int offline_board = 0;
  double offline_start = 0.0, blackout_start = 0.0, slip_start = 0.0;  // s, 0.1 s steps
  bool slip_faster = false;  // odometry_slip scale 1.2, else 0.8
};

struct KidnapSpec {
  double at = 0.0;        // s, 0.1 s steps
  double to_angle = 0.0;  // rad, 4 decimals
};

struct Draft {
  std::string name = "generated";
  double side = 6.0;
  double wall_grey = 0.55;
  double floor = 0.3;
  std::vector<PatternSpec> patterns;  // [0] = wall
  std::vector<LandmarkSpec> landmarks;
  std::vector<ObjectSpec> objects;
  double gap = 0.10;  // near face of every tactile landmark: this far outside the head's path
  double radius = 1.0, speed = 0.1, start_deg = 0.0;
  bool ccw = true;
  int laps = 4;
  double camera_noise = 2.0;
  double sigma_v = 0.005, sigma_omega = 0.003, bias_vy = 0.002, bias_omega = 0.002;
  std::vector<LightChange> light_changes;
  std::vector<FaultSpec> faults;    // none or one: the standard set (--faults)
  std::vector<KidnapSpec> kidnaps;  // --kidnaps
  std::string stress_note;
};

// Angle (deg) of the path that one metre along the head's path spans.
double deg_per_m(const Draft& d, const RobotGeometry& robot);
double head_radius(const Draft& d, const RobotGeometry& robot);

// Draws the arena, its wall landmarks, trajectory, noise and lighting (no tactile landmarks).
void draw_layout(Rng& rng, const GeneratorOptions& o, Draft& d);

// Places tactile landmarks so that every look-alike pair of places is told apart by touch, with a
// feel-alike pair where the views differ. Uses the report of the layout without objects; false if
// the draw cannot be completed within the option's counts.
bool place_objects(Rng& rng, const GeneratorOptions& o, const RobotGeometry& robot, const AliasReport& layout,
                   const Views& views, const AliasCheckParams& check, Draft& d);

// The standard fault set of the robust-SLAM issue, at drawn times within a run of `duration` s.
FaultSpec draw_faults(Rng& rng, double duration);

// `n` kidnaps after the first lap (see world_draft.cpp).
std::vector<KidnapSpec> draw_kidnaps(Rng& rng, const Draft& d, int n);

// The draft as a world file: `comment` (lines without "# ") then the `world:` document.
std::string write_world(const Draft& d, const RobotGeometry& robot, const std::string& comment);

}  // namespace whiskeye::sim::worldgen
