// Template matching: self-match, shifts, per-template minima, terms per mode, σ estimation, size.
#include "whiskeye/slam/template_store.h"
#include "whiskeye/slam/vita_slam.h"

#include "synthetic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace whiskeye::slam {
namespace {

VisualTemplate random_template(uint32_t seed, int w = 64, int h = 40) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> u(0, 255);
  VisualTemplate t;
  t.width = w;
  t.height = h;
  t.pixels.resize(static_cast<size_t>(w * h));
  double sum = 0;
  for (auto& p : t.pixels) {
    p = static_cast<uint8_t>(u(rng));
    sum += p;
  }
  t.mean = static_cast<float>(sum / (w * h) / 255.0);
  return t;
}

// The scene moved right by k columns: current column c shows what stored column c − k showed.
VisualTemplate shifted(const VisualTemplate& a, int k, uint32_t seed) {
  VisualTemplate b = random_template(seed);  // fresh content where nothing overlaps
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const int src = x - k;
      if (src >= 0 && src < a.width) b.pixels[static_cast<size_t>(y * a.width + x)] = a.pixels[static_cast<size_t>(y * a.width + src)];
    }
  return b;
}

TactileTemplate random_tactile(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TactileTemplate t;
  std::array<double, kPfhBins> h{};
  double s = 0;
  for (auto& v : h) s += (v = u(rng) < 0.2 ? u(rng) : 0.0);
  for (int i = 0; i < kPfhBins; ++i) t.pfh[static_cast<size_t>(i)] = static_cast<uint16_t>(std::lround(h[static_cast<size_t>(i)] / s * 65535));
  for (auto& v : t.sda) v = u(rng) < 0.5 ? static_cast<float>(2.0 * u(rng)) : 0.0f;
  t.num_contacts = 12;
  return t;
}

TEST(TemplateMatch, ATemplateMatchesItselfWithErrorZero) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(1);
  const TactileTemplate t = random_tactile(2);
  s.add({&v, &t}, 0, 0, 0);
  for (const Terms terms : {Terms{true, false}, Terms{false, true}, Terms{true, true}}) {
    const BestMatch m = s.match({&v, &t}, terms, MatchParams{});
    EXPECT_EQ(m.id, 0);
    EXPECT_EQ(m.error, 0.0);
    EXPECT_EQ(m.shift, 0);
  }
}

TEST(TemplateMatch, AColumnShiftedImageMatchesAtTheRightShift) {
  TemplateStore s(64, 40);
  const VisualTemplate a = random_template(4);
  s.add({&a, nullptr}, 0, 0, 0);
  for (int k = -5; k <= 5; ++k) {
    const VisualTemplate b = shifted(a, k, 100 + static_cast<uint32_t>(k + 5));
    const BestMatch m = s.match({&b, nullptr}, {true, false}, MatchParams{});
    EXPECT_EQ(m.shift, k);
    EXPECT_EQ(m.error, 0.0) << k;  // the overlap is identical
  }
  // Beyond the allowed shift no overlap is identical.
  const VisualTemplate far = shifted(a, 8, 7);
  EXPECT_GT(s.match({&far, nullptr}, {true, false}, MatchParams{}).error, 0.1);
}

TEST(TemplateMatch, ShiftStepSkipsOddShifts) {
  TemplateStore s(64, 40);
  const VisualTemplate a = random_template(5);
  s.add({&a, nullptr}, 0, 0, 0);
  MatchParams p;
  p.shift_step = 2;
  const VisualTemplate b4 = shifted(a, 4, 8), b3 = shifted(a, 3, 9);
  EXPECT_EQ(s.match({&b4, nullptr}, {true, false}, p).shift, 4);
  EXPECT_GT(s.match({&b3, nullptr}, {true, false}, p).error, 0.1);
}

// The original code never reset the visual minimum between templates, so a template's visual error
// could be that of an earlier, visually better template. Here: template 0 looks the same but feels
// different; template 1 feels the same but looks very different. With the defect template 1 would
// inherit template 0's zero visual error and win; correctly, template 0 wins.
TEST(TemplateMatch, EveryTemplateGetsItsOwnVisualMinimum) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(10);
  const VisualTemplate other = random_template(11);
  const TactileTemplate t = random_tactile(12);
  TactileTemplate t_other = t;  // feels a little different
  t_other.sda[0] += 1.0f;
  s.add({&v, &t_other}, 0, 0, 0);
  s.add({&other, &t}, 0, 0, 0);
  const MatchParams p;
  const BestMatch m = s.match({&v, &t}, {true, true}, p);
  EXPECT_EQ(m.id, 0);
  EXPECT_EQ(m.visual, 0.0);
  // And template 1 on its own reports its own (large) visual term.
  TemplateStore only1(64, 40);
  only1.add({&other, &t}, 0, 0, 0);
  const BestMatch m1 = only1.match({&v, &t}, {true, true}, p);
  EXPECT_GT(m1.visual, m.pfh + m.sda);
  EXPECT_EQ(m1.pfh + m1.sda, 0.0);
}

TEST(TemplateMatch, OnlyTheTermsInUseCount) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(20), v2 = random_template(21);
  const TactileTemplate t = random_tactile(22), t2 = random_tactile(23);
  s.add({&v, &t2}, 0, 0, 0);   // same look, other feel
  s.add({&v2, &t}, 0, 0, 0);   // other look, same feel
  EXPECT_EQ(s.match({&v, &t}, {true, false}, MatchParams{}).id, 0);
  EXPECT_EQ(s.match({&v, &t}, {false, true}, MatchParams{}).id, 1);
  const BestMatch vis = s.match({&v, &t}, {true, false}, MatchParams{});
  EXPECT_EQ(vis.pfh, 0.0);
  EXPECT_EQ(vis.sda, 0.0);
}

// The original code compared only 23 of 24 SDA values and 26 of 27 PFH bins: here a difference in
// any single entry, including the last ones, shows in its term.
TEST(TemplateMatch, EveryPfhBinAndSdaEntryCounts) {
  TemplateStore s(64, 40);
  const TactileTemplate t{};
  s.add({nullptr, &t}, 0, 0, 0);
  for (int bin : {0, kPfhBins / 2, kPfhBins - 1}) {
    TactileTemplate q{};
    q.pfh[static_cast<size_t>(bin)] = 65535;
    const BestMatch m = s.match({nullptr, &q}, {false, true}, MatchParams{});
    EXPECT_NEAR(m.pfh, 1.0 / MatchParams{}.sigma_pfh, 1e-12) << bin;
    EXPECT_EQ(m.sda, 0.0);
  }
  for (int w : {0, 11, kSdaSize - 1}) {
    TactileTemplate q{};
    q.sda[static_cast<size_t>(w)] = 2.0f;
    const BestMatch m = s.match({nullptr, &q}, {false, true}, MatchParams{});
    EXPECT_NEAR(m.sda, 2.0 / MatchParams{}.sigma_sda, 1e-12) << w;
    EXPECT_EQ(m.pfh, 0.0);
  }
}

TEST(TemplateMatch, TemplatesLackingAPartInUseAreNotCandidates) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(30);
  const TactileTemplate t = random_tactile(31);
  s.add({nullptr, &t}, 0, 0, 0);
  EXPECT_EQ(s.match({&v, &t}, {true, true}, MatchParams{}).id, -1);
  EXPECT_EQ(s.match({&v, &t}, {false, true}, MatchParams{}).id, 0);
}

// The fusion (Terms::fused): vision decides (threshold_visual) unless touch differs by more than
// tactile_veto; where both cycles touched something, touch may also add evidence (ε ≤ threshold_vita).
TEST(TemplateMatch, FusedVisionDecidesUnlessTouchClearlyDisagreesAndTouchAddsEvidence) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(50);
  const TactileTemplate t = random_tactile(51);
  s.add({&v, &t}, 0, 0, 0);
  VisualTemplate v2 = v;  // the same view, a little different
  for (size_t k = 0; k < v2.pixels.size(); k += 7) v2.pixels[k] = static_cast<uint8_t>(v2.pixels[k] ^ 0x10);
  MatchParams unit;
  unit.sigma_visual = 1.0;
  const double raw_v = s.match({&v2, &t}, {true, false}, unit).visual;
  ASSERT_GT(raw_v, 0.0);
  TactileTemplate t2 = t;  // the same feel at another phase of the whisk: one SDA entry off by 3
  t2.sda[5] += 3.0f;
  const Terms fused{true, true, true}, sum{true, true};
  MatchParams p;  // τ_V 0.1, τ_vita 0.3
  p.tactile_veto = 0.5;
  // V/σ_V = 0.08 (vision alone would match), touch 0.3 off: the sum (0.38) refuses, the fusion
  // takes vision's word, on threshold_vita's scale (0.08 × 0.3/0.1).
  p.sigma_visual = raw_v / 0.08;
  p.sigma_sda = 3.0 / 0.3;
  EXPECT_GT(s.match({&v2, &t2}, sum, p).error, p.threshold_vita);
  const BestMatch a = s.match({&v2, &t2}, fused, p);
  EXPECT_EQ(a.id, 0);
  EXPECT_NEAR(a.error, 0.24, 1e-9);
  EXPECT_NEAR(a.sda, 0.3, 1e-6);
  // Touch 0.8 off (beyond the veto): it objects, and the sum decides (0.88).
  p.sigma_sda = 3.0 / 0.8;
  EXPECT_NEAR(s.match({&v2, &t2}, fused, p).error, 0.88, 1e-6);
  // V/σ_V = 0.15 (vision alone would not match) with touch 0.1 off: the evidence of both (0.25).
  p.sigma_visual = raw_v / 0.15;
  p.sigma_sda = 3.0 / 0.1;
  const BestMatch c = s.match({&v2, &t2}, fused, p);
  EXPECT_NEAR(c.error, 0.25, 1e-6);
  EXPECT_LE(c.error, p.threshold_vita);
}

// Where vision recognises a place touch does not object to, vision's choice is the match, even if
// another template's view and touch together sum lower; the evidence of both counts only where vision
// recognises nothing, and never for a view beyond threshold_visual_touched.
TEST(TemplateMatch, FusedVisionChoosesFirstAndTouchVouchesOnlyForANearMiss) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(70);
  const TactileTemplate t = random_tactile(71);
  VisualTemplate v2 = v;  // a view a little different
  for (size_t k = 0; k < v2.pixels.size(); k += 5) v2.pixels[k] = static_cast<uint8_t>(v2.pixels[k] ^ 0x20);
  TactileTemplate t2 = t;  // the same feel at another phase: one SDA entry off by 3
  t2.sda[3] += 3.0f;
  s.add({&v2, &t}, 0, 0, 0);  // 0: the view a little off, the touch exactly
  s.add({&v, &t2}, 0, 0, 0);  // 1: the view exactly, the touch a little off
  MatchParams unit;
  unit.sigma_visual = 1.0;
  TemplateStore view_only(64, 40);
  view_only.add({&v2, &t}, 0, 0, 0);
  const double raw_v = view_only.match({&v, &t}, {true, false}, unit).visual;  // template 0's view against v
  ASSERT_GT(raw_v, 0.0);
  const Terms fused{true, true, true};
  MatchParams p;
  p.tactile_veto = 0.5;
  p.sigma_visual = raw_v / 0.05;  // template 0: V 0.05, touch 0 → the sum 0.05
  p.sigma_sda = 3.0 / 0.2;        // template 1: V 0, touch 0.2 → the sum 0.2, vision 0
  const BestMatch m = s.match({&v, &t}, fused, p);
  EXPECT_EQ(m.id, 1);  // vision's choice, not the lower sum
  EXPECT_EQ(m.error, 0.0);
  // Template 1 alone vetoed (touch 0.6 off): vision recognises template 0, V 0.05 → 0.15.
  p.sigma_sda = 3.0 / 0.6;
  EXPECT_EQ(s.match({&v, &t}, fused, p).id, 0);
  EXPECT_NEAR(s.match({&v, &t}, fused, p).error, 0.15, 1e-9);
  // Template 0's view 0.15 off: beyond vision; touch identical vouches for it (0.15 ≤ 0.2) ...
  p.sigma_visual = raw_v / 0.15;
  const BestMatch near_miss = s.match({&v, &t}, fused, p);
  EXPECT_EQ(near_miss.id, 0);
  EXPECT_NEAR(near_miss.error, 0.15, 1e-9);
  EXPECT_LE(near_miss.error, p.threshold_vita);
  // ... but not for a view 0.25 off, though the sum (0.25) is within threshold_vita.
  p.sigma_visual = raw_v / 0.25;
  EXPECT_GT(s.match({&v, &t}, fused, p).error, p.threshold_vita);
  p.threshold_visual_touched = 0.3;
  EXPECT_NEAR(s.match({&v, &t}, fused, p).error, 0.25, 1e-9);
}

// The localiser's question, template by template: recognised by the match's rules, seen only
// (vision alone would take it; touch objects), or neither.
TEST(TemplateMatch, RecogniserTellsRecognisedFromSeenOnlyFromNeither) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(60);
  const TactileTemplate touched = random_tactile(61);
  const TactileTemplate empty{};
  s.add({&v, &touched}, 0, 0, 0);                                    // 0: this view, a contact
  s.add({&v, &empty}, 0, 0, 0);                                      // 1: this view, nothing touched
  const VisualTemplate other = random_template(62);
  s.add({&other, &empty}, 0, 0, 0);                                  // 2: another view
  const MatchParams p;
  const Terms fused{true, true, true};
  const TemplateStore::Recogniser felt_nothing(s, {&v, &empty}, fused, p, p.threshold_vita);
  EXPECT_EQ(felt_nothing(1), Recognition::Recognised);
  EXPECT_EQ(felt_nothing(0), Recognition::SeenOnly) << "an empty PFH is 1/σ_PFH from a contact's: touch objects";
  EXPECT_EQ(felt_nothing(2), Recognition::None);
  EXPECT_EQ(felt_nothing(3), Recognition::None) << "no such template";
  // Vision alone: no veto, so no 'seen only'.
  const TemplateStore::Recogniser seen(s, {&v, nullptr}, {true, false, false}, p, p.threshold_visual);
  EXPECT_EQ(seen(0), Recognition::Recognised);
  EXPECT_EQ(seen(1), Recognition::Recognised);
  EXPECT_EQ(seen(2), Recognition::None);
  // The Recogniser passes what match() would pick.
  const BestMatch m = s.match({&v, &touched}, fused, p);
  EXPECT_EQ(m.id, 0);
  EXPECT_EQ(TemplateStore::Recogniser(s, {&v, &touched}, fused, p, p.threshold_vita)(m.id), Recognition::Recognised);
}

// One routine computes a template's terms for both: the Recogniser takes a template exactly when
// match()'s error for it is within τ, to the last bit (its visual term was divided by σ where
// match() multiplied by 1/σ, and the two disagreed at τ), and it refuses a query of another size as
// match() does (it answered "none").
TEST(TemplateMatch, TheRecogniserAgreesWithTheMatchToTheLastBitAndRefusesWhatItRefuses) {
  MatchParams p;
  p.sigma_visual = 0.123;  // x / 0.123 and x · (1/0.123) differ in the last bit for about half of all x
  p.sigma_pfh = 0.7;
  p.sigma_sda = 1.3;
  const VisualTemplate query = random_template(1000);
  const TactileTemplate felt = random_tactile(1001);
  for (const Terms terms : {Terms{true, false, false}, Terms{false, true, false}, Terms{true, true, false}}) {
    for (uint32_t k = 0; k < 40; ++k) {
      TemplateStore s(64, 40);
      const VisualTemplate v = random_template(k);
      const TactileTemplate t = random_tactile(500 + k);
      s.add({&v, &t}, 0, 0, 0);
      const Query q{&query, &felt};
      const BestMatch m = s.match(q, terms, p);
      ASSERT_EQ(m.id, 0);
      EXPECT_EQ(TemplateStore::Recogniser(s, q, terms, p, m.error)(0), Recognition::Recognised) << k;
      EXPECT_EQ(TemplateStore::Recogniser(s, q, terms, p, std::nextafter(m.error, 0.0))(0), Recognition::None) << k;
    }
  }
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(1);
  s.add({&v, nullptr}, 0, 0, 0);
  const VisualTemplate small = random_template(2, 32, 20);
  EXPECT_THROW(s.match({&small, nullptr}, {true, false, false}, p), std::invalid_argument);
  EXPECT_THROW(TemplateStore::Recogniser(s, {&small, nullptr}, {true, false, false}, p, 1.0), std::invalid_argument);
}

TEST(TemplateMatch, FusedAnEmptyTouchIsNotTakenForAContactNorAContactForAnEmptyTouch) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(60);
  const TactileTemplate touched = random_tactile(61);
  const TactileTemplate empty{};
  s.add({&v, &touched}, 0, 0, 0);
  const Terms fused{true, true, true};
  // An empty PFH is 1/σ_PFH (0.67) from any contact's: beyond the veto, and no evidence either.
  EXPECT_EQ(s.match({&v, &empty}, fused, MatchParams{}).id, -1);
  s.add({&v, &empty}, 0, 0, 0);
  const BestMatch m = s.match({&v, &empty}, fused, MatchParams{});
  EXPECT_EQ(m.id, 1);
  EXPECT_EQ(m.error, 0.0);
  EXPECT_EQ(s.match({&v, &touched}, fused, MatchParams{}).id, 0);
  // A veto wide enough lets vision decide between them.
  MatchParams wide;
  wide.tactile_veto = 10.0;
  TemplateStore only_touched(64, 40);
  only_touched.add({&v, &touched}, 0, 0, 0);
  EXPECT_EQ(only_touched.match({&v, &empty}, fused, wide).id, 0);
}

TEST(TemplateMatch, AWhiskerWithoutDataCountsNeitherAsAgreementNorAsDisagreement) {
  TemplateStore s(64, 40);
  TactileTemplate stored{};
  stored.sda[0] = 4.0f;  // whisker 0 touched when the template was made
  stored.num_contacts = 1;
  s.add({nullptr, &stored}, 0, 0, 0);
  TactileTemplate q{};  // whisker 0's board is offline now: no data, read as no contact
  q.num_contacts = 1;
  q.sda[1] = 2.3f;      // and whisker 1 differs by 2.3
  MatchParams p;
  p.sigma_sda = 1.0;
  // With every whisker sensed both differences count.
  EXPECT_NEAR(s.match({nullptr, &q}, {false, true}, p).sda, 6.3, 1e-5);
  // Without whisker 0 only whisker 1's counts, scaled to the whole array (24/23).
  q.sensed = kAllWhiskersSensed & ~1u;
  EXPECT_NEAR(s.match({nullptr, &q}, {false, true}, p).sda, 2.3 * 24.0 / 23.0, 1e-5);
  q.sensed = 0;  // nothing sensed: no SDA evidence at all
  EXPECT_EQ(s.match({nullptr, &q}, {false, true}, p).sda, 0.0);
}

TEST(TemplateMatch, AWhiskerWithoutDataWhenTheTemplateWasMadeCountsNeither) {
  // A template learnt while boards 0-2 (whiskers 0-11) were offline holds no deflection there; the same
  // place felt later with every whisker differs from it only where the template had no data.
  TemplateStore s(64, 40);
  TactileTemplate stored{};
  stored.num_contacts = 1;
  stored.sda[12] = 1.0f;
  stored.sensed = kAllWhiskersSensed & ~0xfffu;
  s.add({nullptr, &stored}, 0, 0, 0);
  EXPECT_EQ(s.sensed(0), kAllWhiskersSensed & ~0xfffu);
  TactileTemplate q = stored;
  q.sensed = kAllWhiskersSensed;
  for (int w = 0; w < 12; ++w) q.sda[static_cast<size_t>(w)] = 3.0f;  // the whiskers back online
  q.sda[12] = 1.5f;
  MatchParams p;
  p.sigma_sda = 1.0;
  // Only the 12 whiskers both sensed count, scaled to the whole array: 0.5 x 24/12.
  EXPECT_NEAR(s.match({nullptr, &q}, {false, true}, p).sda, 1.0, 1e-5);
  // The same in the localiser's recogniser, and between stored templates (the sigma estimate).
  EXPECT_EQ(TemplateStore::Recogniser(s, {nullptr, &q}, {false, true}, p, 1.01)(0), Recognition::Recognised);
  EXPECT_EQ(TemplateStore::Recogniser(s, {nullptr, &q}, {false, true}, p, 0.99)(0), Recognition::None);
  s.add({nullptr, &q}, 0, 0, 0);
  EXPECT_NEAR(s.estimate_sigmas(p).sigma_sda, 0.0, 1e-12) << "one pair: no spread";
  TemplateStore three = s;
  three.add({nullptr, &q}, 0, 0, 0);  // distances 1, 1, 0 (the two healthy ones agree)
  EXPECT_NEAR(three.estimate_sigmas(p).sigma_sda, std::sqrt(1.0 / 3.0), 1e-6);
}

// A saved map's template with a NaN (or impossible) visual mean or SDA entry is refused by name: the
// prefilter compares the means, and a NaN SDA makes every tactile distance NaN.
TEST(TemplateMatch, ACheckpointedTemplateWithANonFiniteMeanOrSdaIsRefused) {
  for (const int which : {0, 1, 2}) {
    TemplateStore s(64, 40);
    VisualTemplate v = random_template(90);
    TactileTemplate t = random_tactile(91);
    if (which == 0) v.mean = std::nanf("");
    if (which == 1) v.mean = 1.5f;  // a mean intensity is in [0, 1]
    if (which == 2) t.sda[5] = std::numeric_limits<float>::infinity();
    s.add({&v, &t}, 1, 2, 3);
    std::vector<uint8_t> blob;
    s.serialise(blob);
    size_t pos = 0;
    try {
      TemplateStore::deserialise(blob, pos, 64, 40, VitaSlam::kCheckpointFormat);
      ADD_FAILURE() << "loaded, case " << which;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(which == 2 ? "SDA" : "visual mean"), std::string::npos) << e.what();
    }
  }
}

TEST(TemplateMatch, TheSensedWhiskersAreCheckpointedAndOlderFormatsReadAsAllSensed) {
  TemplateStore s(64, 40);
  TactileTemplate t = random_tactile(80);
  t.sensed = 0x00ff00u;
  const VisualTemplate v = random_template(81);
  s.add({&v, &t}, 1, 2, 3);
  std::vector<uint8_t> blob;
  s.serialise(blob);
  size_t pos = 0;
  const TemplateStore r = TemplateStore::deserialise(blob, pos, 64, 40, VitaSlam::kCheckpointFormat);
  EXPECT_EQ(pos, blob.size());
  EXPECT_EQ(r.sensed(0), 0x00ff00u);
  // Format 4 ended before the sensed whiskers: the same bytes without them.
  blob.resize(blob.size() - sizeof(uint64_t) - sizeof(uint32_t));
  pos = 0;
  const TemplateStore old = TemplateStore::deserialise(blob, pos, 64, 40, 4);
  EXPECT_EQ(pos, blob.size());
  EXPECT_EQ(old.sensed(0), kAllWhiskersSensed);
}

TEST(TemplateMatch, ErrorTermsAreDividedByTheirSigmas) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(40), v2 = random_template(41);
  const TactileTemplate t = random_tactile(42), t2 = random_tactile(43);
  s.add({&v2, &t2}, 0, 0, 0);
  MatchParams p;
  const BestMatch a = s.match({&v, &t}, {true, true}, p);
  p.sigma_visual *= 2;
  p.sigma_pfh *= 4;
  p.sigma_sda *= 8;
  const BestMatch b = s.match({&v, &t}, {true, true}, p);
  EXPECT_NEAR(b.visual, a.visual / 2, 1e-12);
  EXPECT_NEAR(b.pfh, a.pfh / 4, 1e-12);
  EXPECT_NEAR(b.sda, a.sda / 8, 1e-12);
  EXPECT_NEAR(a.error, a.visual + a.pfh + a.sda, 1e-12);
}

TEST(TemplateMatch, SigmaEstimateIsTheSpreadOfPairwiseDistances) {
  TemplateStore s(64, 40);
  // Three templates differing only in SDA: pairwise SDA distances 1, 3, 2 → sd = 1.
  VisualTemplate v = random_template(50);
  TactileTemplate t0{}, t1{}, t2{};
  t1.sda[0] = 1.0f;
  t2.sda[0] = 3.0f;
  s.add({&v, &t0}, 0, 0, 0);
  s.add({&v, &t1}, 0, 0, 0);
  s.add({&v, &t2}, 0, 0, 0);
  const SigmaEstimate e = s.estimate_sigmas(MatchParams{});
  EXPECT_EQ(e.pairs, 3);
  EXPECT_NEAR(e.sigma_sda, 1.0, 1e-12);
  EXPECT_EQ(e.sigma_visual, 0.0);
  EXPECT_EQ(e.sigma_pfh, 0.0);
}

TEST(TemplateMatch, StoresATemplateInAtMostThreeKilobytes) {
  TemplateStore s(64, 40);
  std::vector<uint8_t> empty, full;
  s.serialise(empty);
  const VisualTemplate v = random_template(60);
  const TactileTemplate t = random_tactile(61);
  for (int i = 0; i < 100; ++i) s.add({&v, &t}, 1, 2, 3);
  s.serialise(full);
  EXPECT_LE(static_cast<double>(full.size() - empty.size()) / 100.0, 3072.0);
  // Exactly what template_store.h says: 2,906 bytes of parts plus 46 of bookkeeping.
  EXPECT_EQ(full.size() - empty.size(), 100u * (64 * 40 + 125 * 2 + 24 * 4 + 46));
  EXPECT_EQ(s.serialised_bytes(), full.size());
}

TEST(TemplateMatch, SerialisationRoundTripsExactly) {
  TemplateStore s(64, 40);
  const VisualTemplate v = random_template(70);
  const TactileTemplate t = random_tactile(71);
  s.add({&v, &t}, 1.5, 2.5, 3.5);
  s.add({nullptr, &t}, 4, 5, 6);
  s.bump_decay(0, 0.5);
  std::vector<uint8_t> blob;
  s.serialise(blob);
  size_t pos = 0;
  const TemplateStore r = TemplateStore::deserialise(blob, pos, 64, 40, VitaSlam::kCheckpointFormat);
  EXPECT_EQ(pos, blob.size());
  EXPECT_TRUE(r == s);
  // Templates of another size than the parameters' are refused before anything is allocated for
  // them (4096 x 4096 made the first chunk of rows 4 GB).
  pos = 0;
  try {
    TemplateStore::deserialise(blob, pos, 4096, 4096, VitaSlam::kCheckpointFormat);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("templates are 64x40, the parameters say 4096x4096"), std::string::npos);
  }
  blob.resize(blob.size() - 3);
  pos = 0;
  EXPECT_THROW(TemplateStore::deserialise(blob, pos, 64, 40, VitaSlam::kCheckpointFormat), std::runtime_error);
}

void expect_same(const BestMatch& a, const BestMatch& b, const std::string& what) {
  EXPECT_EQ(a.id, b.id) << what;
  EXPECT_EQ(a.error, b.error) << what;  // bit-identical, not merely close
  EXPECT_EQ(a.visual, b.visual) << what;
  EXPECT_EQ(a.pfh, b.pfh) << what;
  EXPECT_EQ(a.sda, b.sda) << what;
  EXPECT_EQ(a.shift, b.shift) << what;
}

// A smooth view (as a camera sees it) block-averaged to a template.
VisualTemplate smooth_template(uint32_t seed) {
  const std::vector<uint8_t> img = test::random_image(64, 40, seed);
  VisualTemplate t;
  t.width = 64;
  t.height = 40;
  t.pixels = img;
  double sum = 0;
  for (uint8_t p : img) sum += p;
  t.mean = static_cast<float>(sum / img.size() / 255.0);
  return t;
}

TEST(TemplateMatch, LowerBoundPrefilterNeverChangesTheResult) {
  // Near and exact ties on purpose: duplicates under later ids, shifted copies, smooth and noisy
  // views, templates lacking a part; every query against every combination of terms and shifts.
  TemplateStore s(64, 40);
  std::vector<VisualTemplate> views;
  std::vector<TactileTemplate> touches;
  for (uint32_t i = 0; i < 60; ++i) {
    views.push_back(i % 3 == 0 ? random_template(100 + i) : smooth_template(100 + i));
    touches.push_back(random_tactile(200 + i));
  }
  for (uint32_t i = 0; i < 20; ++i) views.push_back(shifted(views[i], static_cast<int>(i % 7) - 3, 300 + i));
  for (size_t i = 0; i < views.size(); ++i) {
    const TactileTemplate& t = touches[i % touches.size()];
    s.add({i % 11 == 5 ? nullptr : &views[i], i % 13 == 7 ? nullptr : &t}, 0, 0, 0);
    if (i % 9 == 0) s.add({&views[i], &t}, 0, 0, 0);  // an exact duplicate, later id
  }
  std::vector<uint8_t> blob;
  s.serialise(blob);
  size_t pos = 0;
  const TemplateStore restored = TemplateStore::deserialise(blob, pos, 64, 40, VitaSlam::kCheckpointFormat);
  std::vector<Query> queries;
  for (size_t i = 0; i < views.size(); i += 3) queries.push_back({&views[i], &touches[(i + 1) % touches.size()]});
  std::vector<VisualTemplate> fresh;
  for (uint32_t i = 0; i < 10; ++i) fresh.push_back(i % 2 ? smooth_template(900 + i) : shifted(views[i], 2, 950 + i));
  for (size_t i = 0; i < fresh.size(); ++i) queries.push_back({&fresh[i], &touches[i]});
  int compared = 0;
  for (const auto& [shift_max, shift_step] : {std::pair{5, 1}, std::pair{7, 2}, std::pair{0, 1}, std::pair{63, 4}}) {
    MatchParams on;
    on.shift_max = shift_max;
    on.shift_step = shift_step;
    MatchParams off = on;
    off.lower_bound_prefilter = false;
    for (const Terms terms : {Terms{true, false}, Terms{false, true}, Terms{true, true}}) {
      for (size_t qi = 0; qi < queries.size(); ++qi) {
        const std::string what = "query " + std::to_string(qi) + ", shifts ±" + std::to_string(shift_max) + "/" +
                                 std::to_string(shift_step) + ", visual " + std::to_string(terms.visual) +
                                 ", tactile " + std::to_string(terms.tactile);
        const BestMatch plain = s.match(queries[qi], terms, off);
        expect_same(s.match(queries[qi], terms, on), plain, what);
        expect_same(restored.match(queries[qi], terms, on), plain, what + ", restored store");
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 4 * 3 * static_cast<int>(queries.size()));
}

TEST(TemplateMatch, LowerBoundPrefilterWorksOnTemplatesLowerThanOneBlock) {
  // Three rows: no whole 4-row block, so the bound is 0 and prunes nothing, but must not break.
  TemplateStore s(16, 3);
  std::vector<VisualTemplate> views;
  for (uint32_t i = 0; i < 5; ++i) views.push_back(random_template(500 + i, 16, 3));
  for (const VisualTemplate& v : views) s.add({&v, nullptr}, 0, 0, 0);
  MatchParams off;
  off.lower_bound_prefilter = false;
  for (const VisualTemplate& q : views) {
    expect_same(s.match({&q, nullptr}, {true, false}, MatchParams{}), s.match({&q, nullptr}, {true, false}, off), "3 rows");
  }
}

TEST(TemplateMatch, LowerBoundPrefilterNeverChangesTheResultWhileItSwitchesOnAndOff) {
  // Enough templates for the prefilter to rest on noise it cannot prune (visual terms only) and
  // to work again on smooth views, with the best match early, late and duplicated.
  TemplateStore s(64, 40);
  std::vector<VisualTemplate> views;
  for (uint32_t i = 0; i < 900; ++i) views.push_back(i < 400 || i % 5 == 0 ? random_template(2000 + i) : smooth_template(2000 + i));
  // Near-duplicates (±1 grey level of noise) of a few views, spread over the store: the best
  // match is then one of several templates whose errors differ by a hair.
  std::vector<VisualTemplate> noisy;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> d(-1, 1);
  for (int copy = 0; copy < 4; ++copy) {
    for (size_t i : {3u, 450u, 899u, 600u}) {
      VisualTemplate v = views[i];
      for (uint8_t& px : v.pixels) px = static_cast<uint8_t>(std::clamp(px + d(rng), 0, 255));
      noisy.push_back(v);
    }
  }
  size_t next_noisy = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    s.add({&views[i], nullptr}, 0, 0, 0);
    if (i % 50 == 25 && next_noisy < noisy.size()) s.add({&noisy[next_noisy++], nullptr}, 0, 0, 0);
  }
  for (size_t i = 0; i < 900; i += 97) s.add({&views[i], nullptr}, 0, 0, 0);
  std::vector<VisualTemplate> queries0 = {noisy[0], noisy[5], noisy[10]};
  MatchParams on;
  MatchParams off = on;
  off.lower_bound_prefilter = false;
  std::vector<VisualTemplate> queries = {views[3], views[450], views[899], shifted(views[600], 2, 7), smooth_template(77),
                                         random_template(78)};
  queries.insert(queries.end(), queries0.begin(), queries0.end());
  for (size_t i : {3u, 450u, 899u, 600u}) {  // yet another noisy look at the four places
    VisualTemplate v = views[i];
    for (uint8_t& px : v.pixels) px = static_cast<uint8_t>(std::clamp(px + d(rng), 0, 255));
    queries.push_back(v);
  }
  for (size_t qi = 0; qi < queries.size(); ++qi) {
    const Query q{&queries[qi], nullptr};
    expect_same(s.match(q, {true, false}, on), s.match(q, {true, false}, off), "query " + std::to_string(qi));
  }
}

}  // namespace
}  // namespace whiskeye::slam
