#include "whiskeye/common/robot_geometry.h"

#include <cmath>
#include <string>
#include <vector>

namespace whiskeye {

namespace {

// Layout parameters from which the 24 whiskers are generated.
struct Layout {
  std::vector<double> lengths_by_row{0.0604, 0.0810, 0.1115, 0.1717};  // m; board positions
  std::vector<double> bend_gain_by_row{0.012, 0.016, 0.022, 0.034};    // longer whiskers bend more
  double column_spacing = 0.02;      // m, along head x between columns of one side
  double row_spacing = 0.015;        // m, along head z between rows
  double front_column_x = 0.04;      // m, head x of the front column
  double side_offset = 0.035;        // m, |head y| of the whisker bases
  double azimuth0_front_deg = 60.0;  // direction at θ = 0 of the front column, from head x
  double azimuth_step_deg = 12.0;    // each column further back points this much more laterally
  double elevation_top_deg = 20.0;   // top row elevation
  double elevation_step_deg = -13.0; // per row downwards
  double base_diameter = 1.0e-3;
  double tip_diameter = 0.2e-3;
};

RobotGeometry generate(const Layout& layout, const RobotGeometry& base) {
  RobotGeometry g = base;
  for (int row = 0; row < kWhiskerRows; ++row) {
    for (int column = 0; column < kWhiskerColumns; ++column) {
      WhiskerGeometry& w = g.whiskers[static_cast<std::size_t>(row * kWhiskerColumns + column)];
      const int along = column % 3;  // 0 front .. 2 back
      w.row = row;
      w.column = column;
      w.side = column < 3 ? 1.0 : -1.0;
      w.p_base_in_head = {layout.front_column_x - along * layout.column_spacing, w.side * layout.side_offset,
                          (1.5 - row) * layout.row_spacing};
      w.azimuth0 = w.side * deg_to_rad(layout.azimuth0_front_deg + along * layout.azimuth_step_deg);
      w.elevation = deg_to_rad(layout.elevation_top_deg + row * layout.elevation_step_deg);
      w.length = layout.lengths_by_row[static_cast<std::size_t>(row)];
      w.bend_gain = layout.bend_gain_by_row[static_cast<std::size_t>(row)];
      w.base_diameter = layout.base_diameter;
      w.tip_diameter = layout.tip_diameter;
    }
  }
  return g;
}

void load_vec3(const ParamNode& n, const std::string& key, Vec3& v) {
  std::vector<double> xyz{v.x, v.y, v.z};
  n.get(key, xyz);
  if (xyz.size() != 3) throw ParamError(n.source() + ": '" + n.path_of(key) + "' must be a list [x, y, z]");
  v = {xyz[0], xyz[1], xyz[2]};
}

}  // namespace

Vec3 RobotGeometry::whisker_direction(int w, double theta) const {
  const WhiskerGeometry& g = whiskers[static_cast<std::size_t>(w)];
  const double az = g.azimuth0 - g.side * theta;
  const double ce = std::cos(g.elevation);
  return {ce * std::cos(az), ce * std::sin(az), std::sin(g.elevation)};
}

Vec3 RobotGeometry::whisker_point(int w, double theta, double r) const {
  const Vec3 d = whisker_direction(w, theta);
  const Vec3& b = whiskers[static_cast<std::size_t>(w)].p_base_in_head;
  return {b.x + r * d.x, b.y + r * d.y, b.z + r * d.z};
}

RobotGeometry default_robot_geometry() { return generate(Layout{}, RobotGeometry{}); }

double head_path_radius(double base_radius, const RobotGeometry& robot) {
  return std::hypot(base_radius + robot.T_base_head.x, robot.T_base_head.y);
}

void load(const ParamNode& node, RobotGeometry& geometry) {
  RobotGeometry base = geometry;
  const ParamNode head = node.section("head");
  std::vector<double> mount{base.T_base_head.x, base.T_base_head.y, base.T_base_head.theta};
  head.get("mount_in_base", mount);
  if (mount.size() != 3) throw ParamError(node.source() + ": 'head.mount_in_base' must be [x, y, yaw]");
  base.T_base_head = {mount[0], mount[1], mount[2]};
  head.get("height", base.head_height, 0.0, 2.0);

  const ParamNode cam = node.section("camera");
  cam.get("width", base.camera.width, 16, 8192);
  cam.get("height", base.camera.height, 16, 8192);
  cam.get("hfov", base.camera.hfov, 0.1, 3.0);
  cam.get("fps", base.camera.fps, 0.1, 120.0);
  load_vec3(cam, "position_in_head", base.camera.p_camera_in_head);

  Layout layout;
  const ParamNode lay = node.section("whisker_layout");
  lay.get("lengths_by_row", layout.lengths_by_row);
  lay.get("bend_gain_by_row", layout.bend_gain_by_row);
  for (const char* key : {"lengths_by_row", "bend_gain_by_row"}) {
    const auto& v = std::string(key) == "lengths_by_row" ? layout.lengths_by_row : layout.bend_gain_by_row;
    if (v.size() != kWhiskerRows) {
      throw ParamError(node.source() + ": '" + lay.path_of(key) + "' must have 4 values (one per row)");
    }
    for (double x : v) {
      if (!(x > 0.0 && x < 1.0)) throw ParamError(node.source() + ": '" + lay.path_of(key) + "' values must be in (0, 1)");
    }
  }
  lay.get("column_spacing", layout.column_spacing, 0.0, 0.2);
  lay.get("row_spacing", layout.row_spacing, 0.0, 0.2);
  lay.get("front_column_x", layout.front_column_x, -0.5, 0.5);
  lay.get("side_offset", layout.side_offset, 0.0, 0.5);
  lay.get("azimuth0_front_deg", layout.azimuth0_front_deg, 0.0, 180.0);
  lay.get("azimuth_step_deg", layout.azimuth_step_deg, -90.0, 90.0);
  lay.get("elevation_top_deg", layout.elevation_top_deg, -90.0, 90.0);
  lay.get("elevation_step_deg", layout.elevation_step_deg, -90.0, 90.0);
  lay.get("base_diameter", layout.base_diameter, 1e-5, 1e-2);
  lay.get("tip_diameter", layout.tip_diameter, 1e-6, 1e-2);
  geometry = generate(layout, base);
}

}  // namespace whiskeye
