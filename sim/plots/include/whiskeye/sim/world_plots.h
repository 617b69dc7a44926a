// Pictures of a world: the world drawn into a figure (walls, visual and tactile landmarks; the one
// drawing of a world that vita-sim's map and vita-eval's plots share), vita-sim's top-down map of it
// (--plot-world, PNG and SVG through the figure) and its noise-free camera views (--plot-views).
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/figure/figure.h"
#include "whiskeye/sim/world.h"

#include <string>
#include <vector>

namespace whiskeye::sim {

// Walls, visual landmarks (coloured by pattern: landmarks that look alike share a colour; labelled
// with their pattern on the arena's side) and tactile landmarks (labelled above or below), in the
// world frame.
void draw_world(figure::FigurePanel& panel, const World& world);
// What draw_world's colours mean, for the figure's legend.
void world_legend(figure::Figure& fig);

// Top-down map: the world (draw_world), the base's trajectory, the head's path and the start pose,
// titled with the trajectory's laps, radius, speed and direction. Throws std::runtime_error naming
// `path` if it cannot be written.
void plot_world(const World& world, const RobotGeometry& robot, const std::string& path);

// Noise-free camera views at the given polar angles of the trajectory, tiled two per row at half
// size with their angle written on them: to check a world's visual aliasing by eye.
void plot_views(const World& world, const RobotGeometry& robot, const std::vector<double>& angles_deg,
                const std::string& path);

}  // namespace whiskeye::sim
