// Unit tests of vita-eval's compound option values (whiskeye/eval/options.h).
#include "whiskeye/eval/options.h"

#include <gtest/gtest.h>

namespace whiskeye::eval {
namespace {

TEST(FalseClosureTolerance, SetsMetresAndDegrees) {
  EvalParams p;
  EXPECT_EQ(parse_false_closure_tolerance("0.3,20", p), "");
  EXPECT_DOUBLE_EQ(p.false_closure_position_m, 0.3);
  EXPECT_NEAR(p.false_closure_angle_rad, deg_to_rad(20.0), 1e-15);
  EXPECT_EQ(parse_false_closure_tolerance(" 0.5 , 180", p), "");  // spaces allowed, 180 deg the widest
  EXPECT_DOUBLE_EQ(p.false_closure_position_m, 0.5);
}

TEST(FalseClosureTolerance, TheDefaultSpelledOutIsTheDefault) {
  EvalParams p;
  const EvalParams defaults;
  EXPECT_EQ(parse_false_closure_tolerance("0.25,15", p), "");
  EXPECT_DOUBLE_EQ(p.false_closure_position_m, defaults.false_closure_position_m);
  EXPECT_NEAR(p.false_closure_angle_rad, defaults.false_closure_angle_rad, 1e-15);
}

TEST(FalseClosureTolerance, RejectsMalformedValuesWithOneLineAndLeavesTheParamsAlone) {
  for (const char* bad : {"", "0.3", "0.3;20", "a,b", "0.3,20,1", "0.3,20x", ",20", "0.3,"}) {
    EvalParams p;
    const std::string error = parse_false_closure_tolerance(bad, p);
    EXPECT_EQ(error, std::string("--false-closure-tolerance must be M,DEG (metres, degrees), got '") + bad + "'")
        << bad;
    EXPECT_DOUBLE_EQ(p.false_closure_position_m, kFalseClosurePosition_m) << bad;
  }
}

TEST(FalseClosureTolerance, RejectsNonPositiveValuesAndOver180Degrees) {
  for (const char* bad : {"0,15", "-0.3,15", "0.3,0", "0.3,-5", "0.3,181"}) {
    EvalParams p;
    const std::string error = parse_false_closure_tolerance(bad, p);
    EXPECT_NE(error.find("M must be a positive distance and DEG in (0, 180]"), std::string::npos) << bad << ": " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos);
    EXPECT_NEAR(p.false_closure_angle_rad, deg_to_rad(kFalseClosureAngle_deg), 1e-15) << bad;
  }
}

TEST(FalseClosureTolerance, RefusesToleranceNarrowerThanTheCorrectThresholds) {
  EvalParams p;
  EXPECT_NE(parse_false_closure_tolerance("0.05,15", p).find("narrower than the correct-relocalisation thresholds "
                                                             "(0.08 m, 4.6 deg)"),
            std::string::npos);
  EXPECT_NE(parse_false_closure_tolerance("0.25,3", p), "");
  EXPECT_EQ(parse_false_closure_tolerance("0.08,4.6", p), "") << "equal to the thresholds is allowed";
  p.correct_position_m = 0.3;  // --position-threshold 0.3
  EXPECT_NE(parse_false_closure_tolerance("0.25,15", p), "");
}

}  // namespace
}  // namespace whiskeye::eval
