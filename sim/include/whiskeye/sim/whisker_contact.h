// Whisker/world contact geometry of vita-sim. A whisker is a straight segment from its base along
// RobotGeometry::whisker_direction(w, θ) of its length; protraction sweeps it about the head's
// vertical axis through the base at a fixed elevation. For the current head pose this finds the
// smallest protraction angle in a range at which the segment first meets a world surface (a tactile
// solid's footprint within its height range, or a wall / landmark panel), and the radial distance of
// that contact along the whisker. The plant model (rcp_whisking's WhiskerPlant) turns that into
// θ, deflection and contact in closed loop with the real RCP controller.
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/sim/world.h"

#include <optional>

namespace whiskeye::sim {

struct SweepParams {
  double theta_lo = -35.0 * kPi / 180.0;  // rad, sweep start (retracted)
  double theta_hi = 50.0 * kPi / 180.0;   // rad, sweep end (protracted)
  double step = 0.5 * kPi / 180.0;        // rad, coarse step; thinner features may be missed
  int bisections = 16;                    // refine the first touching angle to step / 2^16
};

struct WhiskerContact {
  double theta = 0.0;       // rad, protraction angle of the first touch
  double radial = 0.0;      // m, from the whisker base along the whisker
  Vec3 p_contact_in_head;   // m, the touching point at that angle
  double stiffness = 1.0;   // the touched surface's stiffness scale (panels: 1)
  int solid = -1;           // index of the touched solid, -1 for a wall or landmark panel
};

// The first contact of whisker w swept from theta_lo to theta_hi with the head at T_world_head
// (planar; the head's height is robot.head_height). nullopt if nothing is touched in the range.
std::optional<WhiskerContact> find_whisker_contact(const World& world, const RobotGeometry& robot,
                                                   const Pose2& T_world_head, int w,
                                                   const SweepParams& sweep = {});

}  // namespace whiskeye::sim
