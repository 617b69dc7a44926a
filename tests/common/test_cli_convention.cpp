// Every program follows the one command-line convention (whiskeye/common/cli.h; docs/deployment.md,
// "Command-line convention"): --version, --help, a bad command line or a missing config as one line
// "<program>: <reason>" and exit 2, and --print-config showing the command line's overrides.
#include "subprocess.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <ostream>
#include <regex>
#include <string>
#include <vector>

namespace whiskeye {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using testing::Subprocess;

struct Program {
  std::string name;
  std::string exe;
  // What the program needs on every command line (CLI11 reports a missing one before a stray option).
  std::vector<std::string> required;
  // Arguments naming a config file that does not exist; empty: the program reads no config.
  std::vector<std::string> missing_config;
};

void PrintTo(const Program& p, std::ostream* out) { *out << p.name; }

const char* const kMissing = "/nonexistent/whiskeye-test.yaml";

std::vector<Program> programs() {
  return {
      {"whiskerd", WHISKERD_EXE, {}, {"-c", kMissing}},
      {"camerad", CAMERAD_EXE, {}, {"-c", kMissing}},
      {"based", BASED_EXE, {}, {"-c", kMissing}},
      {"slamd", SLAMD_EXE, {}, {"-c", kMissing}},
      {"rcp-plant", RCP_PLANT_EXE, {}, {"-c", kMissing}},
      // vita-sim's configs are named by what they hold; --robot has no existence check of its own.
      {"vita-sim", VITA_SIM_EXE, {},
       {"--robot", kMissing, "--world", WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml", "-o", "/dev/null"}},
      {"vita-eval", VITA_EVAL_EXE, {"--input", "/dev/null"}, {}},
      {"whiskeye-logcheck", LOGCHECK_EXE, {"/dev/null"}, {}},
      {"whiskeye-calibrate", CALIBRATE_EXE, {"bus"}, {"bus", "-c", kMissing}},
      {"whiskeye-viewer", VIEWER_EXE, {}, {}},
  };
}

std::vector<Program> programs_with_a_config() {
  std::vector<Program> out;
  for (const Program& p : programs()) {
    if (!p.missing_config.empty()) out.push_back(p);
  }
  return out;
}

// Runs `exe args...`; returns its exit status and (stdout and stderr together) output.
std::pair<int, std::string> run(const std::string& exe, std::vector<std::string> args) {
  args.insert(args.begin(), exe);
  Subprocess p(args);
  const int status = p.wait(30);
  return {status, p.output()};
}

std::size_t lines(const std::string& text) { return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')); }

class ProgramCli : public ::testing::TestWithParam<Program> {};

TEST_P(ProgramCli, PrintsItsNameAndTheBuildsVersion) {
  const auto [status, out] = run(GetParam().exe, {"--version"});
  EXPECT_EQ(status, 0) << out;
  // "<program> <project version>", then the git description in brackets when built from git.
  const std::regex format(GetParam().name + " " + WHISKEYE_VERSION + R"(( \([0-9a-zA-Z.+_-]+\))?)" + "\n");
  EXPECT_TRUE(std::regex_match(out, format)) << out;
}

TEST_P(ProgramCli, HelpExitsZeroWithAUsageLine) {
  const auto [status, out] = run(GetParam().exe, {"--help"});
  EXPECT_EQ(status, 0) << out;
  EXPECT_THAT(out, HasSubstr("Usage: " + GetParam().name));
  EXPECT_THAT(out, HasSubstr("--version"));
}

TEST_P(ProgramCli, AnUnknownOptionIsOneLineNamingTheProgramAndExit2) {
  std::vector<std::string> args = GetParam().required;
  args.push_back("--no-such-option");
  const auto [status, out] = run(GetParam().exe, args);
  EXPECT_EQ(status, 2) << out;
  EXPECT_EQ(lines(out), 1u) << out;  // nothing on stdout, one line on stderr
  EXPECT_EQ(out.rfind(GetParam().name + ": ", 0), 0u) << out;
  EXPECT_THAT(out, HasSubstr("--no-such-option"));
}

TEST_P(ProgramCli, AMissingRequiredArgumentIsOneLineAndExit2) {
  if (GetParam().required.empty()) return;  // nothing is required
  const auto [status, out] = run(GetParam().exe, {});
  EXPECT_EQ(status, 2) << out;
  EXPECT_EQ(lines(out), 1u) << out;
  EXPECT_EQ(out.rfind(GetParam().name + ": ", 0), 0u) << out;
}

class ProgramWithAConfig : public ::testing::TestWithParam<Program> {};

TEST_P(ProgramWithAConfig, AMissingConfigIsOneLineNamingTheFileAndExit2) {
  const auto [status, out] = run(GetParam().exe, GetParam().missing_config);
  EXPECT_EQ(status, 2) << out;
  EXPECT_EQ(lines(out), 1u) << out;
  EXPECT_EQ(out.rfind(GetParam().name + ": ", 0), 0u) << out;
  EXPECT_THAT(out, HasSubstr(kMissing));
}

// 420 bytes of nested YAML aliases (9^9 scalars expanded): refused at its first anchor, at once.
TEST_P(ProgramWithAConfig, AConfigWithYamlAliasesIsOneLineNamingItsLineAndExit2EvenForPrintConfig) {
  const std::string bomb = ::testing::TempDir() + "whiskeye_alias_bomb_" + GetParam().name + ".yaml";
  {
    std::ofstream out(bomb);
    out << "a: &a [x, x, x, x, x, x, x, x, x]\n";
    for (char c = 'b'; c <= 'i'; ++c) {
      out << c << ": &" << c << " [*" << static_cast<char>(c - 1);
      for (int k = 1; k < 9; ++k) out << ", *" << static_cast<char>(c - 1);
      out << "]\n";
    }
  }
  std::vector<std::string> args = GetParam().missing_config;
  std::replace(args.begin(), args.end(), std::string(kMissing), bomb);
  if (GetParam().name != "vita-sim") args.push_back("--print-config");  // vita-sim has no --print-config
  const auto [status, out] = run(GetParam().exe, args);
  std::remove(bomb.c_str());
  EXPECT_EQ(status, 2) << "-1: still expanding after 30 s\n" << out;
  EXPECT_EQ(lines(out), 1u) << out;
  EXPECT_EQ(out.rfind(GetParam().name + ": ", 0), 0u) << out;
  EXPECT_THAT(out, HasSubstr(bomb + ": line 1: an anchor (&a): YAML anchors and aliases are not accepted"));
}

std::string test_name(const ::testing::TestParamInfo<Program>& info) {
  std::string name = info.param.name;
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

INSTANTIATE_TEST_SUITE_P(EveryProgram, ProgramCli, ::testing::ValuesIn(programs()), test_name);
INSTANTIATE_TEST_SUITE_P(EveryProgram, ProgramWithAConfig, ::testing::ValuesIn(programs_with_a_config()), test_name);

// --print-config prints what a run would use: the file's values with the command line's over them.
TEST(PrintConfig, SlamdShowsTheModeGivenOnTheCommandLine) {
  const auto [status, out] = run(SLAMD_EXE, {"-c", WHISKEYE_SOURCE_DIR "/config/slam.yaml", "--mode", "tactile",
                                             "--print-config"});
  ASSERT_EQ(status, 0) << out;
  EXPECT_THAT(out, HasSubstr("slam.mode: \"tactile\"  (--mode)\n"));
  EXPECT_THAT(out, Not(HasSubstr("mode: vita")));
}

TEST(PrintConfig, WhiskerdShowsTheInterfaceGpioAndLcmUrlGivenOnTheCommandLine) {
  const auto [status, out] = run(WHISKERD_EXE, {"-c", WHISKEYE_SOURCE_DIR "/config/whiskerd.yaml", "-i", "can9",
                                                "--no-gpio", "--lcm-url", "udpm://239.255.76.67:7669?ttl=0",
                                                "--print-config"});
  ASSERT_EQ(status, 0) << out;
  EXPECT_THAT(out, HasSubstr("can.interface: \"can9\"  (--interface)\n"));
  EXPECT_THAT(out, HasSubstr("gpio.enabled: false  (--no-gpio)\n"));
  EXPECT_THAT(out, HasSubstr("lcm.url: \"udpm://239.255.76.67:7669?ttl=0\"  (--lcm-url)\n"));
  EXPECT_THAT(out, Not(HasSubstr("can0")));
}

TEST(PrintConfig, CameradShowsTheDeviceGivenOnTheCommandLine) {
  const auto [status, out] = run(CAMERAD_EXE, {"-c", WHISKEYE_SOURCE_DIR "/config/camerad.yaml", "-d", "/dev/video9",
                                               "--print-config"});
  ASSERT_EQ(status, 0) << out;
  EXPECT_THAT(out, HasSubstr("camera.device: \"/dev/video9\"  (--device)\n"));
  EXPECT_THAT(out, HasSubstr("camera.match_card: \"\"  (--device)\n"));
  EXPECT_THAT(out, Not(HasSubstr("video0")));
}

TEST(PrintConfig, BasedShowsTheUrlGivenOnTheCommandLine) {
  const auto [status, out] = run(BASED_EXE, {"-c", WHISKEYE_SOURCE_DIR "/config/based.yaml", "--url",
                                             "http://10.0.0.9:8080", "--print-config"});
  ASSERT_EQ(status, 0) << out;
  EXPECT_THAT(out, HasSubstr("url: \"http://10.0.0.9:8080\"  (--url)\n"));
}

TEST(PrintConfig, RcpPlantShowsTheLawNoiseAndCyclesGivenOnTheCommandLine) {
  const auto [status, out] = run(RCP_PLANT_EXE, {"-c", WHISKEYE_SOURCE_DIR "/config/rcp.yaml", "--law", "off",
                                                 "--noise", "0.02", "--cycles", "5", "--print-config"});
  ASSERT_EQ(status, 0) << out;
  EXPECT_THAT(out, HasSubstr("rcp.law: \"off\"  (--law)\n"));
  EXPECT_THAT(out, HasSubstr("plant.noise_sigma: 0.02  (--noise)\n"));
  EXPECT_THAT(out, HasSubstr("run.cycles: 5  (--cycles)\n"));
}

// An override is checked as the file's value would be, and the error names the option.
TEST(PrintConfig, ABadOverrideIsAConfigErrorNamingTheOption) {
  const auto [status, out] = run(SLAMD_EXE, {"--mode", "sonar", "--print-config"});
  EXPECT_EQ(status, 2) << out;
  EXPECT_EQ(lines(out), 1u) << out;
  EXPECT_THAT(out, HasSubstr("slamd: bad config: --mode: 'slam.mode' is an unknown SLAM mode \"sonar\""));
}

}  // namespace
}  // namespace whiskeye
