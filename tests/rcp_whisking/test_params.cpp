// Controller and plant parameters: documented defaults, YAML loading, strict errors naming the key.
#include <gtest/gtest.h>
#include <whiskeye/rcp/params.h>
#include <whiskeye/rcp/plant.h>

#include <string>

using namespace whiskeye;
using namespace whiskeye::rcp;

namespace {
std::string error_of(const std::string& yaml) {
  try {
    ControllerParams p;
    const ParamNode node = ParamNode::from_string(yaml, "test.yaml");
    load(node, p);
    node.check_no_unknown_keys();
  } catch (const ParamError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(RcpParams, DefaultsAreTheWhiskEyeValues) {
  const ControllerParams p;
  EXPECT_DOUBLE_EQ(p.pattern.frequency_hz, 1.0);
  EXPECT_NEAR(rad_to_deg(p.pattern.theta_min), -30.0, 1e-12);
  EXPECT_NEAR(rad_to_deg(p.pattern.theta_max), 45.0, 1e-12);
  EXPECT_NEAR(rad_to_deg(p.rcp.theta_rcp), -60.0, 1e-12);
  EXPECT_EQ(p.rcp.law, RcpLaw::Whiskeye);
  EXPECT_DOUBLE_EQ(p.detector.threshold_min, 0.04);
  EXPECT_DOUBLE_EQ(p.detector.contact_gain, 5.0);
  EXPECT_NO_THROW(validate(p));
}

TEST(RcpParams, LoadsValuesFromYaml) {
  ControllerParams p;
  const ParamNode node = ParamNode::from_string(
      "pattern: {frequency_hz: 2.5, theta_max_deg: 40, waveform: triangle, row_phase: [0, 0.1, 0.2, 0.3]}\n"
      "detector: {noise_quantile: 0.6, noise_factor: 5}\n"
      "rcp: {law: rate_limited, rate_limit: 3.0, freeze_on_contact: false}\n");
  load(node, p);
  node.check_no_unknown_keys();
  EXPECT_DOUBLE_EQ(p.pattern.frequency_hz, 2.5);
  EXPECT_NEAR(p.pattern.theta_max, deg_to_rad(40.0), 1e-12);
  EXPECT_EQ(p.pattern.waveform, Waveform::Triangle);
  EXPECT_DOUBLE_EQ(p.pattern.row_phase[3], 0.3);
  EXPECT_DOUBLE_EQ(p.detector.noise_quantile, 0.6);
  EXPECT_DOUBLE_EQ(p.detector.noise_factor, 5.0);
  EXPECT_EQ(p.rcp.law, RcpLaw::RateLimited);
  EXPECT_FALSE(p.rcp.freeze_on_contact);
}

TEST(RcpParams, ErrorsNameTheOffendingKey) {
  EXPECT_NE(error_of("pattern: {frequency_hz: 0}").find("pattern.frequency_hz"), std::string::npos);
  EXPECT_NE(error_of("rcp: {law: gentle}").find("rcp.law"), std::string::npos);
  EXPECT_NE(error_of("pattern: {waveform: square}").find("pattern.waveform"), std::string::npos);
  EXPECT_NE(error_of("pattern: {row_phase: [0, 0.5]}").find("pattern.row_phase"), std::string::npos);
  EXPECT_NE(error_of("pattern: {theta_min_deg: 50}").find("pattern.theta_max_deg"), std::string::npos);
  EXPECT_NE(error_of("detector: {thershold_min: 0.1}").find("detector.thershold_min"), std::string::npos);
  EXPECT_EQ(error_of("rcp: {law: off}"), "");
}

TEST(RcpParams, ShippedConfigLoadsAndEqualsTheDefaults) {
  ControllerParams p;
  const ParamNode node = ParamNode::from_file(std::string(WHISKEYE_SOURCE_DIR) + "/config/rcp.yaml");
  load(node, p);
  node.check_no_unknown_keys();
  const ControllerParams d;
  EXPECT_NEAR(p.pattern.frequency_hz, d.pattern.frequency_hz, 1e-12);
  EXPECT_NEAR(p.pattern.theta_min, d.pattern.theta_min, 1e-12);
  EXPECT_NEAR(p.pattern.theta_max, d.pattern.theta_max, 1e-12);
  EXPECT_NEAR(p.pattern.theta_rest, d.pattern.theta_rest, 1e-12);
  EXPECT_NEAR(p.pattern.theta_limit, d.pattern.theta_limit, 1e-12);
  EXPECT_EQ(p.pattern.waveform, d.pattern.waveform);
  EXPECT_EQ(p.pattern.protraction_fraction, d.pattern.protraction_fraction);
  EXPECT_EQ(p.pattern.row_phase, d.pattern.row_phase);
  EXPECT_EQ(p.pattern.ramp_time, d.pattern.ramp_time);
  EXPECT_EQ(p.pattern.max_rate, d.pattern.max_rate);
  EXPECT_EQ(p.detector.learn_cycles, d.detector.learn_cycles);
  EXPECT_EQ(p.detector.learn_min_samples, d.detector.learn_min_samples);
  EXPECT_EQ(p.detector.default_threshold, d.detector.default_threshold);
  EXPECT_EQ(p.detector.threshold_min, d.detector.threshold_min);
  EXPECT_EQ(p.detector.threshold_max, d.detector.threshold_max);
  EXPECT_EQ(p.detector.noise_quantile, d.detector.noise_quantile);
  EXPECT_EQ(p.detector.noise_factor, d.detector.noise_factor);
  EXPECT_EQ(p.detector.release_ratio, d.detector.release_ratio);
  EXPECT_EQ(p.detector.contact_gain, d.detector.contact_gain);
  EXPECT_EQ(p.rcp.law, d.rcp.law);
  EXPECT_NEAR(p.rcp.theta_rcp, d.rcp.theta_rcp, 1e-12);
  EXPECT_EQ(p.rcp.freeze_on_contact, d.rcp.freeze_on_contact);
  EXPECT_EQ(p.rcp.rate_limit, d.rcp.rate_limit);
}

TEST(PlantParams, DefaultLengthsAreTheWhiskEyeLengthsByRow) {
  const PlantParams p;
  EXPECT_DOUBLE_EQ(p.whisker_length[whisker_index(0, 3)], 0.0604);
  EXPECT_DOUBLE_EQ(p.whisker_length[whisker_index(3, 5)], 0.1717);
  PlantParams q;
  load(ParamNode::from_string("whisker_length_by_row: [0.1, 0.2, 0.3, 0.4]\nnoise_sigma: 0.02\n"), q);
  EXPECT_DOUBLE_EQ(q.whisker_length[whisker_index(2, 1)], 0.3);
  EXPECT_DOUBLE_EQ(q.noise_sigma, 0.02);
  PlantParams r;
  EXPECT_THROW(load(ParamNode::from_string("whisker_length_by_row: [0.1, 0.2]\n"), r), ParamError);
}
