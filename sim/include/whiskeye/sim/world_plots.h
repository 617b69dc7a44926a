// vita-sim's pictures of a world: a top-down map (--plot-world) and noise-free camera views along its
// path (--plot-views), as PNG files. OpenCV core and imgproc draw them, zlib writes them (png_file.h).
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/sim/world.h"

#include <string>
#include <vector>

namespace whiskeye::sim {

// Top-down map: walls, visual landmarks (with their pattern names), tactile solids, the trajectory
// and the start pose. 100 px per metre. Throws std::runtime_error naming `path` if it cannot be written.
void plot_world(const World& world, const RobotGeometry& robot, const std::string& path);

// Noise-free camera views at the given polar angles of the trajectory, tiled two per row at half
// size with their angle written on them: to check a world's visual aliasing by eye.
void plot_views(const World& world, const RobotGeometry& robot, const std::vector<double>& angles_deg,
                const std::string& path);

}  // namespace whiskeye::sim
