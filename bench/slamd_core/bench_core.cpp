// vita-bench: Google Benchmark binary for the ViTa-SLAM core. Results and the command that produced
// them are in docs/performance.md ("## slamd/core").
//   BM_TemplateMatch/<n>           the core's matcher, n stored templates (64×40, ±5 shifts step 1,
//                                  vita mode, every template passing the mean prefilter)
//   BM_TemplateMatchReference/<n>  the same computation as a plain double-precision scalar loop (the
//                                  way OpenRatSLAM / the original ViTa-SLAM code compute it)
//   BM_TemplateMatchVisualOnly/<n>/<on>  visual terms only, random pixels, prefilter on (1) / off (0)
//   BM_TemplateMatchPlainScan/<n>/<isa>  the plain scan (visual only, prefilter off) on each SAD
//                                  implementation the CPU has: 0 scalar, 1 baseline SSE2 (the plain
//                                  reference in the same run), 2 AVX2, 3 AVX-512BW (slamd/core/src/sad.h)
//   BM_PoseCellUpdate              one pose-cell step (21×21×36) with motion
//   BM_ExperienceRelax/<n>         20 relaxation loops over n experiences (chain + loop closures)
//   BM_VisualTemplate, BM_TactileTemplate, BM_Cycle   per-cycle costs around them
#include "sad.h"
#include "synthetic.h"
#include "whiskeye/slam/vita_slam.h"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <random>

namespace whiskeye::slam {
namespace {

constexpr int kW = 64, kH = 40, kShift = 5;

struct Data {
  std::vector<VisualTemplate> visual;
  std::vector<TactileTemplate> tactile;
};

Data random_data(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> px(0, 255);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Data d;
  for (int i = 0; i < n; ++i) {
    VisualTemplate v;
    v.width = kW;
    v.height = kH;
    v.pixels.resize(kW * kH);
    double s = 0;
    for (auto& p : v.pixels) s += (p = static_cast<uint8_t>(px(rng)));
    v.mean = static_cast<float>(s / (kW * kH) / 255.0);
    TactileTemplate t;
    for (auto& b : t.pfh) b = u(rng) < 0.1 ? static_cast<uint16_t>(px(rng) * 100) : 0;
    for (auto& x : t.sda) x = static_cast<float>(u(rng));
    t.num_contacts = 10;
    d.visual.push_back(std::move(v));
    d.tactile.push_back(t);
  }
  return d;
}

MatchParams bench_match_params() {
  MatchParams p;
  p.shift_max = kShift;
  p.shift_step = 1;
  p.prefilter_mean_diff = 0.2;  // enabled, and every random template passes it
  return p;
}

// ---- the reference: plain double-precision scalar code, templates stored as doubles ----
struct ReferenceStore {
  std::vector<std::vector<double>> visual, pfh, sda;
  std::vector<double> mean;
};

ReferenceStore reference_store(const Data& d) {
  ReferenceStore r;
  for (size_t i = 0; i < d.visual.size(); ++i) {
    std::vector<double> v(d.visual[i].pixels.size());
    for (size_t k = 0; k < v.size(); ++k) v[k] = d.visual[i].pixels[k] / 255.0;
    r.visual.push_back(v);
    r.mean.push_back(d.visual[i].mean);
    std::vector<double> p(kPfhBins), s(kSdaSize);
    for (int k = 0; k < kPfhBins; ++k) p[static_cast<size_t>(k)] = d.tactile[i].pfh[static_cast<size_t>(k)] / 65535.0;
    for (int k = 0; k < kSdaSize; ++k) s[static_cast<size_t>(k)] = d.tactile[i].sda[static_cast<size_t>(k)];
    r.pfh.push_back(p);
    r.sda.push_back(s);
  }
  return r;
}

// The last template of `d` as the query, everything before it as the reference's memory.
struct ReferenceSetup {
  ReferenceStore store;
  std::vector<double> v, pfh, sda;
  double mean = 0.0;
};

ReferenceSetup reference_setup(const Data& d) {
  ReferenceSetup s;
  s.store = reference_store(Data{{d.visual.begin(), d.visual.end() - 1}, {d.tactile.begin(), d.tactile.end() - 1}});
  s.v.assign(d.visual.back().pixels.begin(), d.visual.back().pixels.end());
  for (double& x : s.v) x /= 255.0;
  s.pfh.resize(kPfhBins);
  s.sda.resize(kSdaSize);
  for (int k = 0; k < kPfhBins; ++k) s.pfh[static_cast<size_t>(k)] = d.tactile.back().pfh[static_cast<size_t>(k)] / 65535.0;
  for (int k = 0; k < kSdaSize; ++k) s.sda[static_cast<size_t>(k)] = d.tactile.back().sda[static_cast<size_t>(k)];
  s.mean = d.visual.back().mean;
  return s;
}

int reference_match(const ReferenceStore& r, const std::vector<double>& v, double vmean, const std::vector<double>& pfh,
                    const std::vector<double>& sda, const MatchParams& p, double* best_error) {
  int best = -1;
  double best_e = 0.0;
  for (size_t i = 0; i < r.visual.size(); ++i) {
    if (std::abs(r.mean[i] - vmean) > p.prefilter_mean_diff) continue;
    double vmin = 1e300;  // reset for every template
    for (int s = -p.shift_max; s <= p.shift_max; s += p.shift_step) {
      double sum = 0.0;
      int count = 0;
      for (int y = 0; y < kH; ++y) {
        for (int x = 0; x < kW; ++x) {
          const int xs = x - s;
          if (xs < 0 || xs >= kW) continue;
          sum += std::abs(v[static_cast<size_t>(y * kW + x)] - r.visual[i][static_cast<size_t>(y * kW + xs)]);
          ++count;
        }
      }
      vmin = std::min(vmin, sum / count);
    }
    double ep = 0.0, es = 0.0;
    for (int k = 0; k < kPfhBins; ++k) ep += std::abs(pfh[static_cast<size_t>(k)] - r.pfh[i][static_cast<size_t>(k)]);
    for (int k = 0; k < kSdaSize; ++k) es += std::abs(sda[static_cast<size_t>(k)] - r.sda[i][static_cast<size_t>(k)]);
    const double e = vmin / p.sigma_visual + ep / p.sigma_pfh + es / p.sigma_sda;
    if (best < 0 || e < best_e) {
      best = static_cast<int>(i);
      best_e = e;
    }
  }
  *best_error = best_e;
  return best;
}

void per_template_counter(benchmark::State& state, int n) {
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * n);
  state.counters["per_template"] =
      benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_TemplateMatch(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Data d = random_data(n + 1, 7);
  TemplateStore store(kW, kH);
  for (int i = 0; i < n; ++i) store.add({&d.visual[static_cast<size_t>(i)], &d.tactile[static_cast<size_t>(i)]}, 0, 0, 0);
  const Query q{&d.visual.back(), &d.tactile.back()};
  const MatchParams p = bench_match_params();
  // The fast matcher must agree with the reference before its speed means anything.
  {
    double ref_e = 0.0;
    int ref = -2;  // the reference is too slow to check every size; 1000 templates suffice
    if (n <= 1000) {
      const ReferenceSetup r = reference_setup(d);
      ref = reference_match(r.store, r.v, r.mean, r.pfh, r.sda, p, &ref_e);
    }
    const BestMatch m = store.match(q, {true, true}, p);
    if (ref != -2 && (ref != m.id || std::abs(ref_e - m.error) > 1e-6 * std::max(1.0, ref_e))) {
      std::fprintf(stderr, "vita-bench: matcher disagrees with the reference (%d/%g vs %d/%g)\n", m.id, m.error, ref,
                   ref_e);
      std::abort();
    }
  }
  for (auto _ : state) {
    BestMatch m = store.match(q, {true, true}, p);
    benchmark::DoNotOptimize(m);
  }
  per_template_counter(state, n);
}
BENCHMARK(BM_TemplateMatch)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);

// Visual terms only (a cycle without contact), uniformly random pixels: the lower-bound prefilter's
// hardest case, as nothing but the image tells templates apart. Arg 1: prefilter on, 0: the plain
// scan of every template and shift.
void BM_TemplateMatchVisualOnly(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Data d = random_data(n + 1, 11);
  TemplateStore store(kW, kH);
  for (int i = 0; i < n; ++i) store.add({&d.visual[static_cast<size_t>(i)], nullptr}, 0, 0, 0);
  const Query q{&d.visual.back(), nullptr};
  MatchParams p = bench_match_params();
  p.lower_bound_prefilter = state.range(1) != 0;
  for (auto _ : state) {
    BestMatch m = store.match(q, {true, false}, p);
    benchmark::DoNotOptimize(m);
  }
  per_template_counter(state, n);
}
BENCHMARK(BM_TemplateMatchVisualOnly)
    ->Args({10000, 1})
    ->Args({10000, 0})
    ->Args({100000, 0})
    ->Unit(benchmark::kMicrosecond);

// The plain scan (every template, every shift: issue 27's ≤ 2 ms at 10,000 and ≤ 20 ms at 100,000)
// with one SAD implementation forced, so the dispatched one (the fastest the CPU has) is compared
// with the baseline-x86-64 build's in the same run. Skipped where the CPU lacks the instructions.
void BM_TemplateMatchPlainScan(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto isa = static_cast<sad::Isa>(state.range(1));
  state.SetLabel(sad::name(isa));
  if (!sad::supported(isa)) {
    state.SkipWithError("this CPU lacks the instructions");
    for (auto _ : state) {
    }
    return;
  }
  const Data d = random_data(n + 1, 11);
  TemplateStore store(kW, kH);
  for (int i = 0; i < n; ++i) store.add({&d.visual[static_cast<size_t>(i)], nullptr}, 0, 0, 0);
  const Query q{&d.visual.back(), nullptr};
  MatchParams p = bench_match_params();
  p.lower_bound_prefilter = false;
  const sad::Isa before = sad::force(sad::Isa::kScalar);
  const BestMatch want = store.match(q, {true, false}, p);
  sad::force(isa);
  const BestMatch got = store.match(q, {true, false}, p);
  if (got.id != want.id || got.error != want.error || got.shift != want.shift) {
    std::fprintf(stderr, "vita-bench: %s disagrees with the scalar SAD\n", sad::name(isa));
    std::abort();
  }
  for (auto _ : state) {
    BestMatch m = store.match(q, {true, false}, p);
    benchmark::DoNotOptimize(m);
  }
  sad::force(before);
  per_template_counter(state, n);
}
BENCHMARK(BM_TemplateMatchPlainScan)
    ->ArgsProduct({{100, 10000}, {1, 2, 3}})
    ->Args({100000, 1})
    ->Args({100000, 3})
    ->Unit(benchmark::kMicrosecond);

void BM_TemplateMatchReference(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Data d = random_data(n + 1, 7);
  const ReferenceSetup r = reference_setup(d);
  const MatchParams p = bench_match_params();
  for (auto _ : state) {
    double e = 0.0;
    int m = reference_match(r.store, r.v, r.mean, r.pfh, r.sda, p, &e);
    benchmark::DoNotOptimize(m);
    benchmark::DoNotOptimize(e);
  }
  per_template_counter(state, n);
}
BENCHMARK(BM_TemplateMatchReference)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

void BM_PoseCellUpdate(benchmark::State& state) {
  PoseCells pc{PoseCellParams{}};
  for (int i = 0; i < 20; ++i) pc.step(0, 0, 0, 0.1);
  int i = 0;
  for (auto _ : state) {
    // 50 Hz odometry: moving forward, sideways and turning.
    pc.step(0.2, 0.1 * ((i++ / 100) % 2 ? 1 : -1), 0.3, 0.02);
  }
  benchmark::DoNotOptimize(pc.activity().data());
}
BENCHMARK(BM_PoseCellUpdate)->Unit(benchmark::kMicrosecond);

void BM_ExperienceRelax(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  ExperienceMap m;
  Pose2 p;
  m.add_experience(p, Experience{});
  for (int i = 1; i < n; ++i) {
    const Pose2 step{0.1 + noise(rng), noise(rng), 0.05 + noise(rng)};
    p = compose(p, step);
    m.add_experience(p, Experience{});
    m.add_link(i - 1, i, step, i);
    // Loop closures: re-localisations' links (one end recognised), weighted and robust.
    if (i % 100 == 0 && i >= 200) m.add_link(i, i - 126, Pose2{0.0, 0.0, 0.0}, i, 1);
  }
  state.counters["links"] = static_cast<double>(m.links().size());
  for (auto _ : state) m.relax(20);
  benchmark::DoNotOptimize(m.experiences().data());
}
BENCHMARK(BM_ExperienceRelax)->Arg(1000)->Arg(10000)->Unit(benchmark::kMicrosecond);

void BM_VisualTemplate(benchmark::State& state) {
  std::vector<uint8_t> grey = test::random_image(640, 480, 1);
  std::vector<uint8_t> yuyv(640 * 480 * 2, 128);
  for (size_t i = 0; i < grey.size(); ++i) yuyv[2 * i] = grey[i];
  const ImageView im{0, 640, 480, 1280, kPixYuyv, yuyv};
  const VisualParams p;
  for (auto _ : state) {
    VisualTemplate t = make_visual_template(im, p);
    benchmark::DoNotOptimize(t.pixels.data());
  }
}
BENCHMARK(BM_VisualTemplate)->Unit(benchmark::kMicrosecond);

void BM_TactileTemplate(benchmark::State& state) {
  const RobotGeometry g = default_robot_geometry();
  const WhiskCycleInput c = test::whisk_cycle(g, test::random_contacts(5, 16), 0.003, 2);
  const TactileParams p;
  for (auto _ : state) {
    TactileTemplate t = make_tactile_template(c, g, p);
    benchmark::DoNotOptimize(t.pfh.data());
  }
}
BENCHMARK(BM_TactileTemplate)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace whiskeye::slam

BENCHMARK_MAIN();
