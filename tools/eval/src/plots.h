// Plots of evaluated runs (the paper's Fig. 4 and 5, and more), each as PNG and SVG: the experience
// map, the pose trail coloured by time with the re-localisations on it, the re-localisations
// (correct / neighbour miss / false closure with ground truth, their jumps in the map without), and
// the runs side by side.
// A run without ground truth is drawn all the same; with a world (vita-sim's world file) the walls and
// landmarks are drawn under it.
#pragma once

#include "whiskeye/eval/metrics.h"
#include "whiskeye/sim/world.h"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace whiskeye::eval {

struct PlotRun {
  std::string label;  // the table's row label: "vita", "vita#2", ...
  const EvalInput* input = nullptr;
  const EvalResult* result = nullptr;
};

struct PlotScene {
  const sim::World* world = nullptr;  // drawn under the maps when given
  // Where the first VITA_POSE lies in the world, for a run without ground truth (a real robot's):
  // the map is drawn in the world frame by putting its first pose there. Default with a world: the
  // world's trajectory at t = 0 (where vita-sim starts the robot).
  std::optional<Pose2> start;
  EvalParams params;  // the ExM thresholds and the false-closure tolerance, named in the legend
};

// Where a run's map frame lies in the plot and what the axes are: the contract's alignment with
// ground truth; without it, the first pose put at the scene's start; else the map frame itself.
struct Placement {
  Pose2 T_plot_map;
  std::string frame;  // "world frame", "map frame", ...
};
Placement place(const EvalInput& input, const EvalResult& result, const PlotScene& scene);

// The file-name stem of a run label: "vita#2" -> "vita-2" ('#' breaks URLs, make and LaTeX).
std::string plot_stem(const std::string& label);

// Called with each file's path before it is written; throws to refuse it.
using BeforeWrite = std::function<void(const std::string& path)>;

// Writes DIR/<stem>_experience_map, DIR/<stem>_trail and DIR/<stem>_relocalisations, each .png and
// .svg; returns the paths written. Throws std::runtime_error naming a file it cannot write.
std::vector<std::string> plot_run(const std::string& dir, const PlotRun& run, const PlotScene& scene,
                                  const BeforeWrite& before_write = {});

// DIR/comparison.png and .svg: every run's experience map in a panel of its own, side by side at one
// scale (the three modes of an experiment).
std::vector<std::string> plot_comparison(const std::string& dir, const std::vector<PlotRun>& runs,
                                         const PlotScene& scene, const BeforeWrite& before_write = {});

}  // namespace whiskeye::eval
