// The one drawing of a world (draw_world), shared by vita-sim's --plot-world and vita-eval's plots.
#include "whiskeye/sim/world_plots.h"

#include "sim_test_util.h"

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

namespace whiskeye::sim {
namespace {

using figure::FigureItem;

std::vector<FigureItem> drawn(const World& w, const std::string& cls) {
  figure::Figure fig("world");
  figure::FigurePanel& panel = fig.add_panel("world");
  draw_world(panel, w);
  std::vector<FigureItem> out;
  for (const FigureItem& it : panel.items()) {
    if (it.cls == cls) out.push_back(it);
  }
  return out;
}

TEST(WorldPlots, DrawsEveryWallLandmarkAndSolidByName) {
  const World w = load_world_file(test::source_path("config/worlds/aliased_arena.yaml"));
  EXPECT_EQ(drawn(w, "wall").size(), w.walls.size());
  const std::vector<FigureItem> landmarks = drawn(w, "visual-landmark");
  ASSERT_EQ(landmarks.size(), w.landmarks.size());
  EXPECT_EQ(landmarks[0].name, "A_north (stripes)") << "a visual landmark is named with its pattern";
  const std::vector<FigureItem> solids = drawn(w, "tactile-landmark");
  ASSERT_EQ(solids.size(), w.solids.size());
  for (std::size_t i = 0; i < solids.size(); ++i) EXPECT_EQ(solids[i].name, w.solids[i].name);
  EXPECT_EQ(drawn(w, "landmark-label").size(), w.landmarks.size() + w.solids.size());
}

TEST(WorldPlots, LandmarksThatLookAlikeShareAColour) {
  const World w = load_world_file(test::source_path("config/worlds/aliased_arena.yaml"));
  std::map<int, std::vector<figure::Rgb>> by_pattern;
  const std::vector<FigureItem> landmarks = drawn(w, "visual-landmark");
  ASSERT_EQ(landmarks.size(), w.landmarks.size());
  for (std::size_t i = 0; i < landmarks.size(); ++i) by_pattern[w.landmarks[i].pattern].push_back(landmarks[i].colour);
  const auto same = [](figure::Rgb a, figure::Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; };
  std::vector<figure::Rgb> firsts;
  for (const auto& [pattern, colours] : by_pattern) {
    for (const figure::Rgb& c : colours) EXPECT_TRUE(same(c, colours.front())) << "pattern " << pattern;
    for (const figure::Rgb& c : firsts) EXPECT_FALSE(same(c, colours.front())) << "pattern " << pattern;
    firsts.push_back(colours.front());
  }
  EXPECT_EQ(by_pattern.size(), 3u) << "stripes twice, checker, blobs";
}

}  // namespace
}  // namespace whiskeye::sim
