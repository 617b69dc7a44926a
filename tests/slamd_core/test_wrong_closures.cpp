// Wrong closures added on purpose: one per closure the front end makes, where the kind says, seeded.
#include "whiskeye/slam/wrong_closures.h"

#include "whiskeye/slam/experience_map.h"

#include <gtest/gtest.h>

#include <cmath>

namespace whiskeye::slam {
namespace {

// 60 experiences 0.1 m apart on a straight line, the robot at experience `at`.
ExperienceMap line_map(int at) {
  ExperienceMap m;
  for (int i = 0; i < 60; ++i) {
    m.add_experience({0.1 * i, 0.0, 0.0}, Experience{});
    if (i > 0) m.add_link(i - 1, i, {0.1, 0.0, 0.0}, i);
  }
  m.set_current(at);
  return m;
}

const Event kClosure{EventType::Relocalise, 9, 10};
const Event kNothing{EventType::SameExperience, 10, 10};

double distance(const ExperienceMap& m, int a, int b) {
  const Pose2& p = m.experiences()[static_cast<size_t>(a)].pose;
  const Pose2& q = m.experiences()[static_cast<size_t>(b)].pose;
  return std::hypot(p.x - q.x, p.y - q.y);
}

TEST(WrongClosures, RandomAddsOneLinkPerClosureToAnExperienceFarAway) {
  ExperienceMap m = line_map(10);
  WrongClosures w({WrongClosureKind::Random, 7});
  const size_t before = m.links().size();
  EXPECT_EQ(w.on_cycle(kNothing, m, 1000), 0) << "no closure, no wrong one";
  for (int k = 0; k < 20; ++k) EXPECT_EQ(w.on_cycle(kClosure, m, 1000 + k), 1);
  ASSERT_EQ(m.links().size(), before + 20);
  EXPECT_EQ(w.added(), 20);
  for (size_t l = before; l < m.links().size(); ++l) {
    const Link& link = m.links()[l];
    EXPECT_EQ(link.from, 10);
    EXPECT_GE(distance(m, 10, link.to), 1.0);
    EXPECT_GE(link.recognised_ends, 1) << "entered as a re-localisation's link: robust";
  }
}

TEST(WrongClosures, LocalDrawsNearButBeyondANeighbour) {
  ExperienceMap m = line_map(30);
  WrongClosures w({WrongClosureKind::Local, 3});
  const size_t before = m.links().size();
  for (int k = 0; k < 20; ++k) w.on_cycle(kClosure, m, 1000 + k);
  ASSERT_GT(m.links().size(), before);
  for (size_t l = before; l < m.links().size(); ++l) {
    const double d = distance(m, 30, m.links()[l].to);
    EXPECT_GE(d, 0.5 - 1e-9);
    EXPECT_LE(d, 1.5 + 1e-9);
  }
}

// A group: group_size consecutive cycles, each linked to the next experience of one earlier pass.
TEST(WrongClosures, AGroupLinksConsecutiveCyclesToConsecutiveExperiences) {
  ExperienceMap m = line_map(10);
  WrongClosureParams p{WrongClosureKind::Group, 11};
  p.group_size = 5;
  WrongClosures w(p);
  const size_t before = m.links().size();
  EXPECT_EQ(w.on_cycle(kClosure, m, 1000), 1);
  for (int k = 1; k < 5; ++k) EXPECT_EQ(w.on_cycle(kNothing, m, 1000 + k), 1);
  EXPECT_EQ(w.on_cycle(kNothing, m, 2000), 0) << "the group is over";
  ASSERT_EQ(m.links().size(), before + 5);
  const int first = m.links()[before].to;
  EXPECT_GE(distance(m, 10, first), 1.0);
  for (size_t k = 0; k < 5; ++k) EXPECT_EQ(m.links()[before + k].to, first + static_cast<int>(k));
  // The next four closures belong to this group's turn; the fifth starts another.
  for (int k = 0; k < 4; ++k) EXPECT_EQ(w.on_cycle(kClosure, m, 3000 + k), 0);
  EXPECT_EQ(w.on_cycle(kClosure, m, 4000), 1);
}

TEST(WrongClosures, TheSameSeedDrawsTheSameClosures) {
  const auto targets = [](uint64_t seed) {
    ExperienceMap m = line_map(10);
    WrongClosures w({WrongClosureKind::Random, seed});
    std::vector<int> out;
    for (int k = 0; k < 10; ++k) w.on_cycle(kClosure, m, 1000 + k);
    for (const Link& l : m.links()) out.push_back(l.to);
    return out;
  };
  EXPECT_EQ(targets(5), targets(5));
  EXPECT_NE(targets(5), targets(6));
}

TEST(WrongClosures, KindsByName) {
  EXPECT_EQ(wrong_closure_kind("group"), WrongClosureKind::Group);
  EXPECT_EQ(wrong_closure_kind("Group"), std::nullopt);
  EXPECT_STREQ(to_string(WrongClosureKind::Local), "local");
}

}  // namespace
}  // namespace whiskeye::slam
