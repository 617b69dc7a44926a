// The world generator's aliasing check against the hand-made arena, whose aliasing is known.
#include "sim_test_util.h"

#include "whiskeye/sim/world_generator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

namespace whiskeye::sim {
namespace {

AliasCheckParams check_params() { return AliasCheckParams{}; }  // slamd's compiled-in defaults = config/slam.yaml


bool has_pair_near(const AliasReport& r, double a_deg, double b_deg, double tol_deg) {
  auto near = [&](double x, double y) {
    const double d = std::fmod(std::abs(x - y), 360.0);
    return std::min(d, 360.0 - d) <= tol_deg;
  };
  for (const auto& [pa, pb] : r.place_pairs) {
    const AliasedPlace& A = r.places[static_cast<std::size_t>(pa)];
    const AliasedPlace& B = r.places[static_cast<std::size_t>(pb)];
    auto contains = [&](const AliasedPlace& p, double x) {
      const double span = std::fmod(p.to_deg - p.from_deg + 360.0, 360.0);
      const double off = std::fmod(x - p.from_deg + 360.0, 360.0);
      return off <= span || near(x, p.from_deg) || near(x, p.to_deg);
    };
    if ((contains(A, a_deg) && contains(B, b_deg)) || (contains(A, b_deg) && contains(B, a_deg))) return true;
  }
  return false;
}

TEST(AliasCheck, FindsTheHandMadeArenasLookAlikeStripesAndItsTwoIdenticalBoxes) {
  const AliasReport r = check_aliasing(test::arena_with("", ""), default_robot_geometry(), check_params());
  // Stripes A hang at 90° and 270°: the views there look alike (docs/simulator.md).
  EXPECT_TRUE(has_pair_near(r, 90.0, 270.0, 4.0));
  // The two corrugated boxes feel alike and stand where the views differ (0° checker, 90° stripes).
  ASSERT_EQ(r.feel_alike_pairs_apart.size(), 1u);
  EXPECT_EQ(r.feel_alike_pairs_apart[0], std::make_pair(std::string("box_east"), std::string("box_north")));
  // The post feels like neither box.
  for (const auto& c : r.feel_alike_classes) {
    if (std::find(c.begin(), c.end(), "post_south") != c.end()) {
      EXPECT_EQ(c.size(), 1u);
    }
  }
}

TEST(AliasCheck, ALookAlikePairWithTheSameTouchIsNotToldApart) {
  // The post at 270° replaced by a corrugated box like the one at 90°: stripes + box at both places.
  const World twin = test::arena_with("    - name: post_south\n      shape: circle\n      pose: [0.0, -1.41, 0.0]\n      radius: 0.06\n",
                                "    - name: box_south\n      shape: polygon\n      pose: [0.0, -1.35, -90.0]\n"
                                "      points: [[0.10, -0.08], [0.10, 0.08], [0.0, 0.08], [0.015, 0.06], [0.0, 0.04], "
                                "[0.015, 0.02], [0.0, 0.0], [0.015, -0.02], [0.0, -0.04], [0.015, -0.06], [0.0, -0.08]]\n");
  const AliasReport r = check_aliasing(twin, default_robot_geometry(), check_params());
  bool found = false;
  for (const auto& [a, b] : r.untold_pairs) {
    const AliasedPlace& A = r.places[static_cast<std::size_t>(a)];
    const AliasedPlace& B = r.places[static_cast<std::size_t>(b)];
    if (A.touched == B.touched && !A.touched.empty()) found = true;
  }
  EXPECT_TRUE(found) << "the stripes at 90 and 270 with identical boxes must be an untold pair";
  EXPECT_FALSE(r.premise_holds());
}

}  // namespace
}  // namespace whiskeye::sim
