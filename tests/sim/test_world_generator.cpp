// The world generator and its aliasing check: reproducible draws within the documented ranges, the
// premise measured again on the written world, the stress family breaking it, the check itself
// against the hand-made arena (whose aliasing is known), and the CLI's errors.
#include "sim_test_util.h"

#include "whiskeye/sim/world_generator.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

namespace whiskeye::sim {
namespace {

namespace fs = std::filesystem;

AliasCheckParams check_params() { return AliasCheckParams{}; }  // slamd's compiled-in defaults = config/slam.yaml

GeneratedWorld generate(uint64_t seed, const std::string& family = "aliased", bool faults = false) {
  GeneratorOptions o;
  o.world_seed = seed;
  o.family = family;
  o.faults = faults;
  return generate_world(o, default_robot_geometry(), check_params());
}

// Generating is the slow part (renders and matches a lap of views per draw): each aliased world the
// tests look at is drawn once.
const GeneratedWorld& aliased(uint64_t seed) {
  static std::map<uint64_t, GeneratedWorld> cache;
  auto it = cache.find(seed);
  if (it == cache.end()) it = cache.emplace(seed, generate(seed)).first;
  return it->second;
}

World arena_with(const std::string& from, const std::string& to) {
  std::ifstream in(test::source_path("config/worlds/aliased_arena.yaml"));
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (!from.empty()) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  const ParamNode root = ParamNode::from_string(text, "<arena>");
  World w;
  load(root.section("world"), w);
  return w;
}

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
  const AliasReport r = check_aliasing(arena_with("", ""), default_robot_geometry(), check_params());
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
  const World twin = arena_with("    - name: post_south\n      shape: circle\n      pose: [0.0, -1.41, 0.0]\n      radius: 0.06\n",
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

TEST(WorldGenerator, SameSeedGivesTheSameWorldAndAnotherSeedAnother) {
  EXPECT_EQ(generate(1).yaml, aliased(1).yaml);
  EXPECT_NE(aliased(1).yaml, aliased(2).yaml);
}

TEST(WorldGenerator, AliasedWorldsAreDrawnWithinTheDocumentedRangesAndKeepThePremise) {
  const World def = arena_with("", "");
  for (uint64_t seed : {1, 2}) {
    SCOPED_TRACE("world seed " + std::to_string(seed));
    const GeneratedWorld& g = aliased(seed);
    const World& w = g.world;
    ASSERT_EQ(w.walls.size(), 4u);
    const double side = std::abs(w.walls[0].from.x) * 2.0;
    EXPECT_GE(side, 5.0 - 1e-3);
    EXPECT_LE(side, 8.0 + 1e-3);
    EXPECT_GE(w.landmarks.size(), 4u);
    EXPECT_LE(w.landmarks.size(), 8u);
    EXPECT_GE(w.solids.size(), 3u);
    EXPECT_LE(w.solids.size(), 6u);
    EXPECT_GE(w.trajectory.radius, 0.8 - 1e-3);
    EXPECT_LE(w.trajectory.radius, 1.3 + 1e-3);
    EXPECT_GE(w.trajectory.speed, 0.07 - 1e-4);
    EXPECT_LE(w.trajectory.speed, 0.15 + 1e-4);
    EXPECT_GE(w.trajectory.laps, 4);
    EXPECT_LE(w.trajectory.laps, 10);
    EXPECT_GE(w.camera.sigma, 2.0 - 1e-2);
    EXPECT_LE(w.camera.sigma, 6.0 + 1e-2);
    EXPECT_GE(std::abs(w.odometry.bias_vy), 0.5 * def.odometry.bias_vy - 1e-5);
    EXPECT_LE(std::abs(w.odometry.bias_vy), 3.0 * def.odometry.bias_vy + 1e-5);
    EXPECT_GE(w.odometry.sigma_v, 1.0 * def.odometry.sigma_v - 1e-5);
    EXPECT_LE(w.odometry.sigma_v, 2.0 * def.odometry.sigma_v + 1e-5);
    // Several shapes, so touch is not one class.
    std::set<std::string> shapes;
    for (const Solid& s : w.solids) shapes.insert(s.name.substr(0, s.name.rfind('_')));
    EXPECT_GE(shapes.size(), 2u);
    // The premise, measured again on the world as written (not the generator's own bookkeeping).
    const AliasReport r = check_aliasing(w, default_robot_geometry(), check_params());
    EXPECT_GE(r.place_pairs.size(), 2u);
    EXPECT_TRUE(r.untold_pairs.empty());
    EXPECT_FALSE(r.feel_alike_pairs_apart.empty());
    EXPECT_TRUE(r.premise_holds());
    // The header says what was found.
    EXPECT_EQ(g.yaml.rfind("# Generated by vita-sim --generate-world --world-seed " + std::to_string(seed), 0), 0u);
    EXPECT_NE(g.yaml.find("look-alike places"), std::string::npos);
    EXPECT_NE(g.yaml.find("feel-alike tactile landmarks where the views differ: " + r.feel_alike_pairs_apart[0].first),
              std::string::npos);
  }
}

TEST(WorldGenerator, StressWorldsBreakThePremiseAtALookAlikePair) {
  for (uint64_t seed : {1}) {
    const GeneratedWorld g = generate(seed, "stress");
    const AliasReport r = check_aliasing(g.world, default_robot_geometry(), check_params());
    EXPECT_FALSE(r.untold_pairs.empty()) << "seed " << seed;
    EXPECT_NE(g.yaml.find("# stress: premise broken on purpose"), std::string::npos);
  }
}

TEST(WorldGenerator, RefusesBadOptionsNamingThem) {
  GeneratorOptions o;
  o.family = "mirror";
  try {
    validate(o);
    ADD_FAILURE() << "unknown family accepted";
  } catch (const GeneratorOptionError& e) {
    EXPECT_NE(std::string(e.what()).find("--family"), std::string::npos) << e.what();
  }
  o = GeneratorOptions{};
  o.radius = {1.3, 0.8};
  try {
    validate(o);
    ADD_FAILURE() << "empty range accepted";
  } catch (const GeneratorOptionError& e) {
    EXPECT_NE(std::string(e.what()).find("--radius"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("empty"), std::string::npos) << e.what();
  }
  o = GeneratorOptions{};
  o.laps = {4.5, 6};
  EXPECT_THROW(validate(o), GeneratorOptionError);
}

// ---- the executable ----

std::string temp_path(const std::string& name) {
  return (fs::temp_directory_path() / ("world_generator_test_" + std::to_string(getpid()) + "_" + name)).string();
}

int vita_sim(const std::string& args, const std::string& err = "/dev/null") {
  const std::string cmd = std::string(VITA_SIM_EXE) + " --robot " + test::source_path("config/robot.yaml") +
                          " --slam-config " + test::source_path("config/slam.yaml") + " " + args + " 2>" + err;
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(VitaSimGenerate, WritesAWorldTheSimulatorRuns) {
  const std::string world = temp_path("w.yaml");
  ASSERT_EQ(vita_sim("--generate-world --world-seed 2 --output-world " + world), 0);
  const std::string text = slurp(world);
  EXPECT_EQ(text.rfind("# Generated by vita-sim --generate-world --world-seed 2 --family aliased", 0), 0u);
  EXPECT_EQ(text, aliased(2).yaml) << "the CLI writes exactly the library's world";
  const std::string log = temp_path("w.lcmlog");
  EXPECT_EQ(vita_sim("--world " + world + " --duration 2 -q -o " + log), 0);
  EXPECT_GT(fs::file_size(log), 0u);
  fs::remove(world);
  fs::remove(log);
}

TEST(VitaSimGenerate, BadGeneratorOptionsExitTwoNamingTheOption) {
  const std::string err = temp_path("err.txt");
  const std::string out = " --output-world " + temp_path("never.yaml");
  EXPECT_EQ(vita_sim("--generate-world --family mirror" + out, err), 2);
  EXPECT_NE(slurp(err).find("vita-sim: --family: unknown family 'mirror'"), std::string::npos) << slurp(err);
  EXPECT_EQ(vita_sim("--generate-world --radius 1.3,0.8" + out, err), 2);
  EXPECT_NE(slurp(err).find("vita-sim: --radius: the range 1.300..0.800 is empty"), std::string::npos) << slurp(err);
  EXPECT_EQ(vita_sim("--generate-world --speed fast" + out, err), 2);
  EXPECT_NE(slurp(err).find("--speed"), std::string::npos) << slurp(err);
  EXPECT_EQ(vita_sim("--generate-world", err), 2);  // no --output-world
  EXPECT_FALSE(fs::exists(temp_path("never.yaml")));
  fs::remove(err);
}

}  // namespace
}  // namespace whiskeye::sim
