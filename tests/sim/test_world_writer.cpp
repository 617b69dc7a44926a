// The world file writer: what it writes, the loader reads back as written.
#include "sim_test_util.h"

#include "whiskeye/sim/world_writer.h"

#include <gtest/gtest.h>

#include <string>

namespace whiskeye::sim {
namespace {

using Decimal = WorldWriter::Decimal;

TEST(WorldWriter, WritesNumbersAtTheirDecimalsAndNegativeZeroAsZero) {
  EXPECT_EQ(format_decimal(1.23456, 4), "1.2346");
  EXPECT_EQ(format_decimal(0.5, 1), "0.5");
  EXPECT_EQ(format_decimal(-0.00001, 4), "0.0000");
  EXPECT_EQ(format_decimal(-0.5, 2), "-0.50");
}

TEST(WorldWriter, WritesAWorldFileTheLoaderReadsBackAsWritten) {
  WorldWriter y("made by a test\n  indented line");
  y.scalar("name", "written");
  y.scalar("floor_value", Decimal{0.25, 2});
  y.list("patterns", {{{"name", "wall"}, {"type", "solid"}, {"high", Decimal{0.55, 2}}}});
  y.list("walls", {{{"name", "east"},
                    {"from", WorldWriter::Scalars{Decimal{3.0, 4}, Decimal{-3.0, 4}}},
                    {"to", WorldWriter::Scalars{Decimal{3.0, 4}, Decimal{3.0, 4}}},
                    {"pattern", "wall"}}});
  y.list("tactile_landmarks",
         {{{"name", "box"},
           {"pose", WorldWriter::Scalars{Decimal{1.5, 1}, Decimal{0.0, 1}, Decimal{90.0, 1}}},
           {"points", std::vector<WorldWriter::Scalars>{{Decimal{0.1, 1}, Decimal{-0.1, 1}},
                                                       {Decimal{0.1, 1}, Decimal{0.1, 1}},
                                                       {Decimal{0.0, 1}, Decimal{0.0, 1}}}},
           {"pattern", "wall"}}});
  y.begin_section("lighting");
  y.flow_list("changes", {{{"start", Decimal{5.0, 1}}, {"duration", Decimal{0.5, 2}}, {"gain", Decimal{2.0, 2}}}});
  y.end_section();
  y.entry("trajectory", {{"radius", Decimal{1.2, 3}}, {"direction", "cw"}, {"laps", int64_t{3}}});
  y.entry("odometry", {{"start_at_truth", true}});
  y.begin_section("faults");
  y.scalars("dead_whiskers", {int64_t{2}, int64_t{7}});
  y.end_section();
  const std::string text = y.text();

  EXPECT_EQ(text.rfind("# made by a test\n#   indented line\nworld:\n  name: written\n  floor_value: 0.25\n", 0), 0u)
      << text;
  EXPECT_NE(text.find("    - {name: east, from: [3.0000, -3.0000], to: [3.0000, 3.0000], pattern: wall}\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("  trajectory: {radius: 1.200, direction: cw, laps: 3}\n"), std::string::npos) << text;
  EXPECT_EQ(text.back(), '\n');

  const World w = load_world(ParamNode::from_string(text, "<written>"));
  EXPECT_EQ(w.name, "written");
  EXPECT_DOUBLE_EQ(w.floor_value, 0.25);
  ASSERT_EQ(w.walls.size(), 1u);
  EXPECT_DOUBLE_EQ(w.walls[0].from.y, -3.0);
  ASSERT_EQ(w.solids.size(), 1u);
  EXPECT_EQ(w.solids[0].vertices.size(), 3u);
  ASSERT_EQ(w.lighting.changes.size(), 1u);
  EXPECT_DOUBLE_EQ(w.lighting.changes[0].start, 5.0);
  EXPECT_DOUBLE_EQ(w.trajectory.radius, 1.2);
  EXPECT_FALSE(w.trajectory.counter_clockwise);
  EXPECT_EQ(w.trajectory.laps, 3);
  EXPECT_TRUE(w.odometry.start_at_truth);
  EXPECT_EQ(w.faults.dead_whiskers, (std::vector<int>{2, 7}));
}

TEST(WorldWriter, ASectionLeftOpenIsAProgrammingError) {
  WorldWriter y("");
  y.begin_section("lighting");
  EXPECT_THROW(y.text(), std::logic_error);
}

}  // namespace
}  // namespace whiskeye::sim
