// Pose cells: path integration in every direction, rotation, wrap-around, stability, injection.
#include "whiskeye/slam/pose_cells.h"

#include "whiskeye/common/se2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace whiskeye::slam {
namespace {

double wrapped(double d, int n) {
  d = std::fmod(d, static_cast<double>(n));
  if (d > n / 2.0) d -= n;
  if (d < -n / 2.0) d += n;
  return d;
}

struct Best {
  double x, y, t;
};
Best best(const PoseCells& pc) {
  Best b{};
  pc.best(b.x, b.y, b.t);
  return b;
}

PoseCells settled() {
  PoseCells pc{PoseCellParams{}};
  for (int i = 0; i < 20; ++i) pc.step(0, 0, 0, 0.1);
  return pc;
}

// Moves for `seconds` with body velocity (vx, vy) and checks the packet moved by R(heading)·v·t.
void expect_moves(PoseCells pc, double vx, double vy, double seconds, double dt, double min_fraction = 0.9) {
  const Best b0 = best(pc);
  const double heading = b0.t * kTwoPi / pc.params().dim_theta;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  for (int i = 0; i < steps; ++i) pc.step(vx, vy, 0.0, dt);
  const Best b1 = best(pc);
  const double cs = pc.params().cell_size;
  const double ex = (std::cos(heading) * vx - std::sin(heading) * vy) * seconds / cs;
  const double ey = (std::sin(heading) * vx + std::cos(heading) * vy) * seconds / cs;
  const double tol = 0.08 * std::hypot(ex, ey) + 0.15;
  EXPECT_NEAR(wrapped(b1.x - b0.x, pc.params().dim_xy), wrapped(ex, pc.params().dim_xy), tol);
  EXPECT_NEAR(wrapped(b1.y - b0.y, pc.params().dim_xy), wrapped(ey, pc.params().dim_xy), tol);
  EXPECT_NEAR(wrapped(b1.t - b0.t, pc.params().dim_theta), 0.0, 0.2);
  EXPECT_GT(pc.packet_fraction(), min_fraction);
}

TEST(PoseCells, StartsAsOnePacketAtTheCentre) {
  const PoseCells pc = settled();
  const Best b = best(pc);
  EXPECT_NEAR(b.x, 10.0, 1e-6);
  EXPECT_NEAR(b.y, 10.0, 1e-6);
  EXPECT_NEAR(wrapped(b.t, 36), 0.0, 1e-6);
  EXPECT_GT(pc.packet_fraction(), 0.95);
}

TEST(PoseCells, RelocateMovesTheWholeActivityToOnePacketThere) {
  PoseCells pc = settled();
  pc.step(0.1, 0.03, 0.0, 0.5);  // leaves sub-cell remainders behind
  pc.inject(3, 4, 5, 0.3);       // and a second, competing packet
  pc.relocate(17.2, 2.4, 30.0);
  const Best b = best(pc);
  EXPECT_NEAR(b.x, 17.0, 1e-3);
  EXPECT_NEAR(b.y, 2.0, 1e-3);
  EXPECT_NEAR(wrapped(b.t - 30.0, 36), 0.0, 1e-3);
  EXPECT_GT(pc.packet_fraction(), 0.95);
  // Motion after it starts from there, remainders cleared.
  expect_moves(pc, 0.1, 0.0, 5.0, 0.1);
}

TEST(PoseCells, ForwardMotionMovesThePacketAlongTheHeading) { expect_moves(settled(), 0.1, 0.0, 5.0, 0.1); }
TEST(PoseCells, SidewaysMotionMovesThePacketToTheLeft) { expect_moves(settled(), 0.0, 0.1, 5.0, 0.1); }
TEST(PoseCells, BackwardsAndRightMotionMovesThePacketBothWays) { expect_moves(settled(), -0.08, -0.06, 5.0, 0.1); }
TEST(PoseCells, DiagonalMotionMovesThePacketDiagonally) { expect_moves(settled(), 0.1, 0.1, 4.0, 0.1); }

TEST(PoseCells, RotationTurnsThePacketAndThenForwardFollowsTheNewHeading) {
  PoseCells pc = settled();
  for (int i = 0; i < 50; ++i) pc.step(0, 0, kPi / 2 / 5.0, 0.1);  // 90° in 5 s
  const Best b = best(pc);
  EXPECT_NEAR(wrapped(b.t, 36), 9.0, 0.3);
  EXPECT_NEAR(b.x, 10.0, 0.2);
  EXPECT_NEAR(b.y, 10.0, 0.2);
  expect_moves(pc, 0.1, 0.0, 5.0, 0.1);  // now along +y
  expect_moves(pc, 0.0, 0.1, 5.0, 0.1);  // left of +y is −x
}

TEST(PoseCells, ThePacketWrapsAroundTheEdges) {
  PoseCells pc = settled();
  for (int i = 0; i < 300; ++i) pc.step(0.1, 0.0, 0.0, 0.1);  // 30 cells on a 21-cell ring
  const Best b = best(pc);
  EXPECT_NEAR(wrapped(b.x - (10.0 + 30.0), 21), 0.0, 0.08 * 30);
  EXPECT_GT(pc.packet_fraction(), 0.9);
  for (int i = 0; i < 100; ++i) pc.step(0, 0, -kPi / 5.0, 0.1);  // two full turns clockwise
  EXPECT_NEAR(wrapped(best(pc).t, 36), 0.0, 0.4);
}

TEST(PoseCells, FastMotionIsIntegratedCorrectly) {
  // 3.5 cells per step: OpenRatSLAM's one-cell assumption would break; here it is exact. The θ
  // layers of the packet (±20°) fan out by 3.5·sin 20° ≈ 1.2 cells in one step, so right after the
  // step a little less of the activity sits in the best-estimate box.
  expect_moves(settled(), 3.5, 0.0, 0.5, 0.1, 0.75);
  expect_moves(settled(), 0.0, -2.2, 0.5, 0.1, 0.75);
}

TEST(PoseCells, StaysASinglePacketOverTenThousandSteps) {
  PoseCells pc = settled();
  for (int i = 0; i < 10000; ++i) {
    // A wandering trajectory: forward, sideways and turning, changing every few seconds.
    const double ph = i * 0.01;
    pc.step(0.15 * std::cos(0.3 * ph), 0.1 * std::sin(0.7 * ph), 0.4 * std::sin(0.2 * ph), 0.1);
    if (i % 1000 == 999) {
      ASSERT_GT(pc.packet_fraction(), 0.9) << "step " << i;
    }
  }
  double total = 0.0;
  for (float v : pc.activity()) total += v;
  EXPECT_NEAR(total, 1.0, 1e-4);
}

// The network keeps track of where its activity lies (which rows and layers to compute) across
// steps, translations, rotations and injections. A network restored from a checkpoint knows none of
// that and scans every cell: the two must compute the same activity, bit for bit, at every step.
TEST(PoseCells, WhatItKnowsOfWhereActivityLiesNeverChangesTheActivity) {
  PoseCells pc = settled();
  PoseCells fresh{PoseCellParams{}};
  std::vector<uint8_t> state, fresh_state;
  for (int i = 0; i < 600; ++i) {
    const double ph = i * 0.05;
    const double vx = 0.3 * std::cos(0.3 * ph), vy = 0.2 * std::sin(0.7 * ph), omega = 1.5 * std::sin(0.2 * ph);
    state.clear();
    pc.serialise(state);
    size_t pos = 0;
    fresh.deserialise(state, pos);
    if (i % 37 == 5) {
      pc.inject(i % 21, (3 * i) % 21, i % 36, 0.05);
      fresh.inject(i % 21, (3 * i) % 21, i % 36, 0.05);
    }
    pc.step(vx, vy, omega, 0.1);
    fresh.step(vx, vy, omega, 0.1);
    state.clear();
    fresh_state.clear();
    pc.serialise(state);
    fresh.serialise(fresh_state);
    ASSERT_EQ(state, fresh_state) << "step " << i;
  }
}

// The dynamics written plainly: every cell, every tap, the rows and layers nothing reaches too.
// Kernels as the model defines them (1-D Gaussians normalised to 1).
std::vector<float> gaussian(int r, double sigma) {
  std::vector<float> k(static_cast<size_t>(2 * r + 1));
  double sum = 0.0;
  for (int i = -r; i <= r; ++i) sum += std::exp(-0.5 * i * i / (sigma * sigma));
  for (int i = -r; i <= r; ++i) k[static_cast<size_t>(i + r)] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)) / sum);
  return k;
}

std::vector<float> plain_dynamics(const std::vector<float>& p, const PoseCellParams& prm) {
  const int n = prm.dim_xy, nt = prm.dim_theta;
  const auto at = [n](int t, int y, int x) { return (static_cast<size_t>(t) * n + static_cast<size_t>(y)) * n + static_cast<size_t>(x); };
  const auto wrap = [](int i, int m) { return ((i % m) + m) % m; };
  // Along x, then y, then θ: out = Σ_j k[j]·in[i + j − r], wrapped, taps in order, from +0.
  const auto convolve = [&](const std::vector<float>& src, const std::vector<float>& k, int r) {
    std::vector<float> a(src.size()), b(src.size()), c(src.size());
    for (int t = 0; t < nt; ++t) {
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          float s = 0.0f;
          for (int j = 0; j <= 2 * r; ++j) s += k[static_cast<size_t>(j)] * src[at(t, y, wrap(x + j - r, n))];
          a[at(t, y, x)] = s;
        }
      }
    }
    for (int t = 0; t < nt; ++t) {
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          float s = 0.0f;
          for (int j = 0; j <= 2 * r; ++j) s += k[static_cast<size_t>(j)] * a[at(t, wrap(y + j - r, n), x)];
          b[at(t, y, x)] = s;
        }
      }
    }
    for (int t = 0; t < nt; ++t) {
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          float s = 0.0f;
          for (int j = 0; j <= 2 * r; ++j) s += k[static_cast<size_t>(j)] * b[at(wrap(t + j - r, nt), y, x)];
          c[at(t, y, x)] = s;
        }
      }
    }
    return c;
  };
  const std::vector<float> e = convolve(p, gaussian(prm.exc_radius, prm.exc_sigma), prm.exc_radius);
  const std::vector<float> i = convolve(e, gaussian(prm.inh_radius, prm.inh_sigma), prm.inh_radius);
  const auto g = static_cast<float>(prm.global_inhibition);
  std::vector<float> q(p.size());
  double total = 0.0;
  for (int t = 0; t < nt; ++t) {
    for (int y = 0; y < n; ++y) {
      float row_sum = 0.0f;
      for (int x = 0; x < n; ++x) {
        const float v = e[at(t, y, x)] - i[at(t, y, x)];
        q[at(t, y, x)] = v >= g ? v - g : 0.0f;
        row_sum += q[at(t, y, x)];
      }
      total += row_sum;
    }
  }
  EXPECT_GT(total, 0.0);
  const auto inv = static_cast<float>(1.0 / total);
  for (float& v : q) v *= inv;
  return q;
}

// The network computes only where activity can be, a run of rows at a time, in vector-width spans:
// every step must equal the plain full-grid dynamics to the bit. Activity scattered over the grid
// and across its edges, on grids smaller than the kernels and the default one.
TEST(PoseCells, DynamicsEqualThePlainFullGridComputationToTheBit) {
  struct Grid {
    int n, nt, exc_r, inh_r;
  };
  for (const Grid& grid : {Grid{21, 36, 3, 2}, Grid{5, 4, 3, 2}, Grid{8, 6, 10, 7}, Grid{13, 9, 2, 1}}) {
    SCOPED_TRACE("grid " + std::to_string(grid.n) + "x" + std::to_string(grid.n) + "x" + std::to_string(grid.nt) +
                 ", radii " + std::to_string(grid.exc_r) + " and " + std::to_string(grid.inh_r));
    PoseCellParams prm;
    prm.dim_xy = grid.n;
    prm.dim_theta = grid.nt;
    prm.exc_radius = grid.exc_r;
    prm.inh_radius = grid.inh_r;
    PoseCells pc{prm};
    std::mt19937 rng(static_cast<uint32_t>(grid.n * 100 + grid.nt));
    std::uniform_int_distribution<int> cell(-2, 40);
    std::uniform_real_distribution<double> energy(0.01, 0.5);
    for (int step = 0; step < 40; ++step) {
      // Every few steps some energy somewhere, often near (and wrapped across) an edge.
      if (step % 5 == 0) {
        for (int k = 0; k < 1 + step % 3; ++k) pc.inject(cell(rng), cell(rng), cell(rng), energy(rng));
      }
      const std::vector<float> expected = plain_dynamics(pc.activity(), prm);
      pc.settle();
      ASSERT_EQ(pc.activity().size(), expected.size());
      ASSERT_EQ(std::memcmp(pc.activity().data(), expected.data(), expected.size() * sizeof(float)), 0) << "step " << step;
    }
  }
}

// The wrap tables reach kPad (16) cells past an edge; load() caps radii at 10, and a network built
// directly with a wider kernel is refused rather than read past its tables.
TEST(PoseCells, KernelsWiderThanTheWrapTablesAreRefused) {
  PoseCellParams p;
  p.exc_radius = 17;
  EXPECT_THROW(PoseCells{p}, std::invalid_argument);
  PoseCells pc{PoseCellParams{}};
  p = PoseCellParams{};
  p.inh_radius = 40;
  EXPECT_THROW(pc.set_params(p), std::invalid_argument);
  EXPECT_EQ(pc.params().inh_radius, PoseCellParams{}.inh_radius) << "a refused set_params changes nothing";
  p.inh_radius = 16;
  EXPECT_NO_THROW(pc.set_params(p));
}

TEST(PoseCells, RepeatedInjectionMovesTheBestEstimate) {
  PoseCells pc = settled();
  for (int i = 0; i < 30; ++i) {
    pc.inject(3, 15, 20, 0.1);
    pc.step(0, 0, 0, 0.1);
  }
  const Best b = best(pc);
  EXPECT_NEAR(b.x, 3.0, 0.5);
  EXPECT_NEAR(b.y, 15.0, 0.5);
  EXPECT_NEAR(b.t, 20.0, 0.5);
}

// best() is cached; a restored copy computes it afresh, so the two must agree after every kind of
// change — including a sub-cell step, which moves no activity but the carried remainder.
TEST(PoseCells, CachedBestFollowsEveryChange) {
  PoseCells pc = settled();
  auto expect_fresh = [&](const char* after) {
    std::vector<uint8_t> blob;
    pc.serialise(blob);
    PoseCells fresh{pc.params()};
    size_t pos = 0;
    fresh.deserialise(blob, pos);
    const Best cached = best(pc), recomputed = best(fresh);
    EXPECT_EQ(cached.x, recomputed.x) << after;
    EXPECT_EQ(cached.y, recomputed.y) << after;
    EXPECT_EQ(cached.t, recomputed.t) << after;
  };
  expect_fresh("settling");
  const Best before = best(pc);
  pc.step(0.01, 0.0, 0.0, 0.1);  // 0.1 cell: the grid does not move, the estimate does
  EXPECT_NE(best(pc).x, before.x);
  expect_fresh("a sub-cell step");
  pc.step(0.2, 0.1, 0.3, 0.5);
  expect_fresh("a step with motion");
  pc.inject(3, 15, 20, 5.0);
  expect_fresh("an injection");
  pc.settle();
  expect_fresh("settling after the injection");
  PoseCellParams wider;
  wider.best_radius = 6;
  pc.set_params(wider);
  expect_fresh("a new best_radius");
}

TEST(PoseCells, DistanceWrapsOnEveryAxis) {
  const PoseCells pc{PoseCellParams{}};
  EXPECT_NEAR(pc.distance(0.5, 0, 0, 20.5, 0, 0), 1.0, 1e-12);
  EXPECT_NEAR(pc.distance(0, 0, 35, 0, 0, 1), 2.0, 1e-12);
  EXPECT_NEAR(pc.distance(1, 2, 3, 4, 6, 3), 5.0, 1e-12);
}

TEST(PoseCells, SerialisationRestoresTheActivityExactly) {
  PoseCells a = settled();
  a.step(0.1, 0.05, 0.1, 0.1);
  std::vector<uint8_t> blob;
  a.serialise(blob);
  PoseCells b{PoseCellParams{}};
  size_t pos = 0;
  b.deserialise(blob, pos);
  EXPECT_EQ(a.activity(), b.activity());
  PoseCellParams other;
  other.dim_xy = 30;
  PoseCells c{other};
  pos = 0;
  EXPECT_THROW(c.deserialise(blob, pos), std::runtime_error);
}

}  // namespace
}  // namespace whiskeye::slam
