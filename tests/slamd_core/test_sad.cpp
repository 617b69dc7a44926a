// The matcher's SAD kernel: every implementation this CPU supports (the dispatched one among them)
// returns exactly what the byte-at-a-time reference does, on random data and on the edge cases —
// every length around the vector widths, extreme differences, unaligned starts — and the whole
// matcher gives the same match whichever implementation it runs on.
#include "sad.h"

#include "whiskeye/slam/template_store.h"

#include <gtest/gtest.h>

#include <random>
#include <span>
#include <string>
#include <vector>

namespace whiskeye::slam {
namespace {

constexpr sad::Isa kAll[] = {sad::Isa::kScalar, sad::Isa::kBaseline, sad::Isa::kAvx2, sad::Isa::kAvx512bw};

uint32_t reference(const uint8_t* a, const uint8_t* b, size_t n) {
  uint32_t s = 0;
  for (size_t i = 0; i < n; ++i) s += static_cast<uint32_t>(a[i] > b[i] ? a[i] - b[i] : b[i] - a[i]);
  return s;
}

// Each supported implementation against the reference for a and b at offsets oa, ob, n bytes.
void expect_all_agree(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, size_t oa, size_t ob, size_t n,
                      const std::string& what) {
  const uint32_t want = reference(a.data() + oa, b.data() + ob, n);
  for (const sad::Isa isa : kAll) {
    if (!sad::supported(isa)) continue;
    EXPECT_EQ(sad::sad_u8(isa, a.data() + oa, b.data() + ob, n), want) << sad::name(isa) << ", " << what;
  }
  EXPECT_EQ(sad::sad_u8(a.data() + oa, b.data() + ob, n), want) << "dispatched (" << sad::name(sad::selected()) << "), "
                                                                 << what;
}

TEST(Sad, EveryImplementationEqualsTheReferenceOnRandomData) {
  std::mt19937 rng(27);
  std::uniform_int_distribution<int> u(0, 255);
  std::vector<uint8_t> a(4200), b(4200);
  for (int round = 0; round < 20; ++round) {
    for (auto& v : a) v = static_cast<uint8_t>(u(rng));
    for (auto& v : b) v = static_cast<uint8_t>(u(rng));
    // Every length up to 300 (all tails of the 16-, 32-, 64- and 256-byte steps), then the matcher's
    // overlaps at 64x40 (59..64 columns of 40 rows) and the block-mean copies' (10 rows).
    for (size_t n = 0; n <= 300; ++n) expect_all_agree(a, b, 0, 0, n, "n " + std::to_string(n));
    for (size_t cols = 0; cols <= 64; ++cols) {
      const size_t oa = static_cast<size_t>(round % 7), ob = static_cast<size_t>(round % 5);  // unaligned starts
      expect_all_agree(a, b, oa, ob, cols * 40, std::to_string(cols) + " columns of 40, offsets " + std::to_string(oa) +
                                                    "/" + std::to_string(ob));
      expect_all_agree(a, b, ob, oa, cols * 10, std::to_string(cols) + " columns of 10");
    }
  }
}

TEST(Sad, EveryImplementationEqualsTheReferenceAtTheExtremes) {
  // 0 against 255 everywhere: the largest sum (4096·255 at the longest length here), in both
  // directions, and equal runs (0).
  for (const size_t n : {size_t{1}, size_t{15}, size_t{16}, size_t{31}, size_t{63}, size_t{64}, size_t{65}, size_t{255},
                         size_t{2560}, size_t{4096}}) {
    const std::vector<uint8_t> zeros(n, 0), full(n, 255), mixed = [n] {
      std::vector<uint8_t> m(n);
      for (size_t i = 0; i < n; ++i) m[i] = i % 2 ? 255 : 0;
      return m;
    }();
    expect_all_agree(zeros, full, 0, 0, n, "0 vs 255, n " + std::to_string(n));
    expect_all_agree(full, zeros, 0, 0, n, "255 vs 0, n " + std::to_string(n));
    expect_all_agree(mixed, full, 0, 0, n, "alternating vs 255, n " + std::to_string(n));
    expect_all_agree(full, full, 0, 0, n, "equal, n " + std::to_string(n));
    EXPECT_EQ(sad::sad_u8(zeros.data(), full.data(), n), 255u * static_cast<uint32_t>(n));
  }
}

TEST(Sad, ReadsNothingBeyondTheRun) {
  // Runs that end exactly at the end of their allocation, for every tail length: a read past it
  // would be caught by the sanitizer builds (and the masked AVX-512 tail must not fault).
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> u(0, 255);
  for (size_t n = 1; n <= 130; ++n) {
    std::vector<uint8_t> a(n), b(n);
    for (auto& v : a) v = static_cast<uint8_t>(u(rng));
    for (auto& v : b) v = static_cast<uint8_t>(u(rng));
    expect_all_agree(a, b, 0, 0, n, "exact allocation, n " + std::to_string(n));
  }
}

TEST(Sad, AllShiftsAtOnceEqualOneReferenceSadPerShift) {
  // Column-major images; 11 shifts (the fused path) in several spacings and orders, and other counts
  // (one SAD per shift); heights that are and are not a multiple of the vector width; sizes too small
  // for the fused path.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> u(0, 255);
  struct Case {
    int w, h;
    std::vector<int> shifts;
  };
  const std::vector<Case> cases = {
      {64, 40, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}}, {64, 10, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}},
      {64, 40, {0, 2, -2, 4, -4, 6, -6, 8, -8, 10, -10}}, {33, 17, {-5, -4, -3, -2, -1, 0, 1, 2, 3, 4, 5}},
      {80, 64, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}},   {64, 40, {0, 1, -1, 2, -2, 3, -3}},
      {12, 3, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}},    {6, 40, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}},
      // Shifts with no overlap at all (|s| ≥ w); images ending inside a vector (41 rows: 2,624
      // bytes, 0 mod 32 only); a single vector that is all edge.
      {4, 40, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}},    {64, 41, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}},
      {65, 41, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}},   {1, 20, {0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5}},
  };
  for (const Case& c : cases) {
    const size_t n = static_cast<size_t>(c.w) * static_cast<size_t>(c.h);
    for (int round = 0; round < 5; ++round) {
      // Round 3 compares a stored image that starts one byte past an aligned address, and is
      // followed by nothing (a read past it would be caught by ASan).
      std::vector<uint8_t> cur(n), st_buf(n + (round == 3 ? 1 : 0));
      const std::span<uint8_t> st(st_buf.data() + (round == 3 ? 1 : 0), n);
      for (auto& v : cur) v = static_cast<uint8_t>(round == 4 ? 255 : u(rng));
      for (auto& v : st) v = static_cast<uint8_t>(round == 4 ? 0 : u(rng));
      std::vector<uint32_t> want;
      for (const int s : c.shifts) {
        uint32_t sum = 0;
        for (int x = 0; x < c.w; ++x) {
          if (x - s < 0 || x - s >= c.w) continue;
          sum += reference(cur.data() + static_cast<size_t>(x * c.h), st.data() + static_cast<size_t>((x - s) * c.h),
                           static_cast<size_t>(c.h));
        }
        want.push_back(sum);
      }
      for (const sad::Isa isa : kAll) {
        if (!sad::supported(isa)) continue;
        std::vector<uint32_t> got(c.shifts.size());
        sad::shift_sads(isa, cur.data(), st.data(), c.w, c.h, c.shifts.data(), static_cast<int>(c.shifts.size()),
                        got.data());
        EXPECT_EQ(got, want) << sad::name(isa) << ", " << c.w << "x" << c.h << ", " << c.shifts.size() << " shifts";
      }
    }
  }
}

TEST(Sad, TheMatcherGivesTheSameMatchOnEveryImplementation) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> u(0, 255);
  std::vector<VisualTemplate> views(300);
  for (auto& t : views) {
    t.width = 64;
    t.height = 40;
    t.pixels.resize(64 * 40);
    for (auto& p : t.pixels) p = static_cast<uint8_t>(u(rng));
    t.mean = 0.5f;
  }
  // Near-duplicates (±1 grey level on some pixels) so that ties and near-ties decide the match.
  for (size_t i = 0; i < 100; ++i) {
    views.push_back(views[i]);
    for (size_t k = i; k < views.back().pixels.size(); k += 37) views.back().pixels[k] ^= 1;
  }
  TemplateStore s(64, 40);
  for (size_t i = 0; i + 20 < views.size(); ++i) s.add({&views[i], nullptr}, 0, 0, 0);
  const sad::Isa before = sad::selected();
  for (const bool prefilter : {false, true}) {
    MatchParams p;
    p.lower_bound_prefilter = prefilter;
    for (size_t q = views.size() - 20; q < views.size(); ++q) {
      sad::force(sad::Isa::kScalar);
      const BestMatch want = s.match({&views[q], nullptr}, {true, false}, p);
      for (const sad::Isa isa : kAll) {
        if (!sad::supported(isa)) continue;
        sad::force(isa);
        const BestMatch got = s.match({&views[q], nullptr}, {true, false}, p);
        EXPECT_EQ(got.id, want.id) << sad::name(isa);
        EXPECT_EQ(got.shift, want.shift) << sad::name(isa);
        EXPECT_EQ(got.error, want.error) << sad::name(isa);  // bit-identical, not within a tolerance
        EXPECT_EQ(got.visual, want.visual) << sad::name(isa);
      }
    }
  }
  sad::force(before);
}

TEST(Sad, TheFastestSupportedImplementationIsSelected) {
  const sad::Isa before = sad::force(sad::Isa::kScalar);
  sad::force(before);
  const sad::Isa want = sad::supported(sad::Isa::kAvx512bw) ? sad::Isa::kAvx512bw
                        : sad::supported(sad::Isa::kAvx2)   ? sad::Isa::kAvx2
                                                            : sad::Isa::kBaseline;
  EXPECT_EQ(before, want) << sad::name(before);
  EXPECT_TRUE(sad::supported(sad::Isa::kScalar));
  EXPECT_TRUE(sad::supported(sad::Isa::kBaseline));
}

}  // namespace
}  // namespace whiskeye::slam
