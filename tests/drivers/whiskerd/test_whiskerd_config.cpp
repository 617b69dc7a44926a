// whiskerd's configuration (Params / load, config.h): unknown keys, rates, CAN id ranges, the
// shipped config, calibration drop-ins.

#include <grp.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "whiskeye/common/params.h"
#include "whiskeye/whiskerd/config.h"

using namespace whiskeye;
using namespace whiskeye::whiskerd;

TEST(WhiskerdConfig, UnknownKeyIsAnErrorNamingIt) {
  Params p;
  try {
    load(ParamNode::from_string("can:\n  intrface: can1\n"), p);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("can.intrface"), std::string::npos) << e.what();
  }
}

TEST(WhiskerdConfig, ClassicModeDefaultsToAFeasibleRateAndRejectsTooFast) {
  Params p;
  load(ParamNode::from_string("can: {mode: classic}\n"), p);
  EXPECT_EQ(p.mode, wp::BusMode::kClassic);
  EXPECT_EQ(p.rate_hz, 100.0);
  Params q;
  EXPECT_THROW(load(ParamNode::from_string("can: {mode: classic, rate_hz: 500}\n"), q), ParamError);
}

// A board is stale when its last sample is older than stale_timeout_s: under two sample periods,
// every board is stale between its samples and whiskerd never leaves retracting.
TEST(WhiskerdConfig, AStaleTimeoutUnderTwoSamplePeriodsIsRefused) {
  Params p;
  try {
    load(ParamNode::from_string("can: {mode: classic, rate_hz: 10, stale_timeout_s: 0.15}\n"), p);
    FAIL() << "expected a ParamError";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("can.stale_timeout_s = 0.150000 is less than two sample periods"),
              std::string::npos) << e.what();
  }
  Params q;
  EXPECT_NO_THROW(load(ParamNode::from_string("can: {mode: classic, rate_hz: 10, stale_timeout_s: 0.2}\n"), q));
  Params r;  // the shipped 0.1 s at the FD default of 500 Hz
  EXPECT_NO_THROW(load(ParamNode::from_string("can: {stale_timeout_s: 0.1}\n"), r));
}

TEST(WhiskerdConfig, OverlappingIdRangesAreRejected) {
  Params p;
  EXPECT_THROW(load(ParamNode::from_string("can: {ids: {sample_base: 0x200}}\n"), p), ParamError);
}

TEST(WhiskerdConfig, ReceivedIdBasesMustStartAnAlignedBlockOfEight) {
  // The kernel filters cover base .. base+7 with mask 0x7f8: an unaligned base would silently drop
  // the upper boards' frames (0x183: 0x188 and 0x189).
  const std::pair<const char*, const char*> bad[] = {{"sample_base", "0x183"}, {"sample_base", "0x305"},
                                                     {"sample_base", "0x7f1"}, {"heartbeat_base", "0x703"},
                                                     {"heartbeat_base", "0x305"}, {"heartbeat_base", "0x7f1"}};
  for (const auto& [key, base] : bad) {
    Params p;
    const std::string yaml = std::string("can: {ids: {") + key + ": " + base + "}}\n";
    try {
      load(ParamNode::from_string(yaml), p);
      ADD_FAILURE() << yaml << " loaded";
    } catch (const ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("can.ids.") + key), std::string::npos) << e.what();
    }
  }
  Params p;
  load(ParamNode::from_string("can: {ids: {sample_base: 0x188, heartbeat_base: 0x708}}\n"), p);
  EXPECT_EQ(p.ids.sample_base, 0x188u);
  EXPECT_EQ(p.ids.heartbeat_base, 0x708u);
}

TEST(WhiskerdConfig, ShippedConfigLoads) {
  Params p;
  load(ParamNode::from_file(WHISKEYE_SOURCE_DIR "/config/whiskerd.yaml"), p);
  EXPECT_EQ(p.interface, "can0");
  EXPECT_EQ(p.ids.command_base, 0x200u);
}

// Calibration drop-ins: whiskerd.d/*.yaml beside whiskerd.yaml, in file-name order, calibration keys only.
class WhiskerdDropins : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::path(::testing::TempDir()) /
           ("whiskerd_dropins_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_ / "whiskerd.d");
    write("whiskerd.yaml", "calibration:\n  default: {offset_x: 1.0}\n  whiskers:\n    - {index: 3, offset_y: 5.0}\n");
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }
  std::string config() const { return (dir_ / "whiskerd.yaml").string(); }
  // The whole configuration as whiskerd loads it; "" or the ParamError's text.
  std::string load_all(Params& p) const {
    try {
      printed_ = load_with_dropins(ParamNode::from_file(config()), config(), p);
      return "";
    } catch (const ParamError& e) {
      return e.what();
    }
  }
  // A drop-in whiskerd.d/`file` of one whisker entry `{entry}` is refused with "<its path>: `why`".
  void expect_refused(const std::string& file, const std::string& entry, const std::string& why) {
    write("whiskerd.d/" + file, "calibration:\n  whiskers:\n    - {" + entry + "}\n");
    Params p;
    const std::string error = load_all(p);
    EXPECT_NE(error.find((dir_ / "whiskerd.d" / file).string() + ": " + why), std::string::npos) << entry << ": " << error;
  }
  std::filesystem::path dir_;
  mutable std::string printed_;
};

TEST_F(WhiskerdDropins, TheDirectoryIsTheConfigsNameWithDotD) {
  EXPECT_EQ(dropin_dir("/etc/whiskeye/whiskerd.yaml"), std::filesystem::path("/etc/whiskeye/whiskerd.d"));
}

TEST_F(WhiskerdDropins, ADropinReplacesOnlyTheKeysItGives) {
  write("whiskerd.d/20-rest.yaml", "calibration:\n  whiskers:\n    - {index: 3, offset_x: 12.5}\n    - {index: 7, gain_y: -0.0005}\n");
  Params p;
  ASSERT_EQ(load_all(p), "");
  EXPECT_EQ(p.calibration[3].offset_x, 12.5);
  EXPECT_EQ(p.calibration[3].offset_y, 5.0);  // from whiskerd.yaml
  EXPECT_EQ(p.calibration[4].offset_x, 1.0);  // whiskerd.yaml's default
  EXPECT_EQ(p.calibration[7].gain_y, -0.0005);
  EXPECT_EQ(p.calibration[7].gain_x, wp::WhiskerCalibration{}.gain_x);
  EXPECT_NE(printed_.find("# drop-in " + (dir_ / "whiskerd.d/20-rest.yaml").string()), std::string::npos) << printed_;
}

TEST_F(WhiskerdDropins, LaterFilesWinInFileNameOrder) {
  // Written in the other order: the directory's listing order must not matter.
  write("whiskerd.d/40-theta.yaml", "calibration:\n  whiskers:\n    - {index: 0, theta_offset: 40}\n");
  write("whiskerd.d/10-map.yaml", "calibration:\n  default: {theta_offset: 10}\n  whiskers:\n    - {index: 1, theta_offset: 11}\n");
  write("whiskerd.d/README", "not a drop-in: only *.yaml are read\n");
  Params p;
  ASSERT_EQ(load_all(p), "");
  EXPECT_EQ(p.calibration[0].theta_offset, 40);
  EXPECT_EQ(p.calibration[1].theta_offset, 11);
  EXPECT_EQ(p.calibration[2].theta_offset, 10);
}

TEST_F(WhiskerdDropins, ATypoIsOneLineNamingTheFileAndTheKey) {
  write("whiskerd.d/20-rest.yaml", "calibration:\n  whiskers:\n    - {index: 3, ofset_x: 12.5}\n");
  Params p;
  const std::string error = load_all(p);
  EXPECT_NE(error.find((dir_ / "whiskerd.d/20-rest.yaml").string()), std::string::npos) << error;
  EXPECT_NE(error.find("calibration.whiskers[0].ofset_x"), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
}

TEST_F(WhiskerdDropins, AKeyOutsideCalibrationIsRefused) {
  write("whiskerd.d/50-bus.yaml", "can: {interface: can1}\n");
  Params p;
  const std::string error = load_all(p);
  EXPECT_NE(error.find("50-bus.yaml: 'can' is not allowed in a drop-in"), std::string::npos) << error;
}

// A second document was never read: neither the `can:` a drop-in may not hold, nor whiskerd.yaml's own.
TEST_F(WhiskerdDropins, ASecondDocumentInADropinOrTheConfigIsRefused) {
  write("whiskerd.d/50-bus.yaml", "calibration:\n  default: {offset_x: 2.0}\n---\ncan: {interface: vcan9}\n");
  Params p;
  std::string error = load_all(p);
  EXPECT_NE(error.find("50-bus.yaml: line 3: a second YAML document"), std::string::npos) << error;
  std::filesystem::remove(dir_ / "whiskerd.d/50-bus.yaml");
  write("whiskerd.yaml", "can: {interface: can0}\n---\ncan: {interface: vcan9}\n");
  Params q;
  error = load_all(q);
  EXPECT_NE(error.find("whiskerd.yaml: line 2: a second YAML document"), std::string::npos) << error;
}

TEST_F(WhiskerdDropins, AnOutOfRangeValueNamesTheFileAndTheKey) {
  write("whiskerd.d/30-gain.yaml", "calibration:\n  whiskers:\n    - {index: 2, gain_x: 3.0}\n");
  Params p;
  const std::string error = load_all(p);
  EXPECT_NE(error.find("30-gain.yaml"), std::string::npos) << error;
  EXPECT_NE(error.find("calibration.whiskers[0].gain_x"), std::string::npos) << error;
}

// The bounds whiskeye-calibrate writes within (kCalibrationBounds): a dead whisker (gain 0), 2047x
// nominal, a theta gain of 1e-300 or a rotation in degrees loaded with exit 0 before.
TEST_F(WhiskerdDropins, AnImplausibleCalibrationIsRefusedNamingTheFileTheKeyAndTheValue) {
  const std::pair<const char*, const char*> bad[] = {
      {"gain_x: 0", "'calibration.whiskers[0].gain_x' = 0 is outside the plausible 0.5..2 x nominal (1/2047) in magnitude"},
      {"gain_y: 1.0", "'calibration.whiskers[0].gain_y' = 1 is outside the plausible 0.5..2 x nominal"},
      {"gain_x: -1.0", "'calibration.whiskers[0].gain_x' = -1 is outside the plausible"},
      {"theta_gain: 1e-300", "'calibration.whiskers[0].theta_gain' = 1e-300 is outside the plausible 0.8..1.25 x nominal (2 pi / 4096)"},
      {"rotation: 7", "'calibration.whiskers[0].rotation' = 7 is outside the plausible ±1.5708 rad (±90 deg)"},
      {"offset_y: -600", "'calibration.whiskers[0].offset_y' = -600 is outside the plausible ±512 counts"},
      {"theta_offset: 300", "'calibration.whiskers[0].theta_offset' = 300 is outside the plausible ±256 counts"}};
  for (const auto& [entry, why] : bad) expect_refused("30-gain.yaml", std::string("index: 2, ") + entry, why);
  // whiskerd.yaml's own calibration, its default for every whisker included, the same.
  std::filesystem::remove(dir_ / "whiskerd.d/30-gain.yaml");
  write("whiskerd.yaml", "calibration:\n  default: {gain_x: 0.0}\n");
  Params q;
  EXPECT_NE(load_all(q).find("whiskerd.yaml: 'calibration.default.gain_x' = 0 is outside the plausible"), std::string::npos);
  // The edges are plausible: a mirrored board, twice nominal, a quarter turn.
  write("whiskerd.yaml", "calibration:\n  whiskers:\n    - {index: 2, gain_x: -0.000977, gain_y: 0.000245, "
                         "rotation: -1.5707963267948966, theta_gain: -0.0019, offset_x: 512}\n");
  Params r;
  EXPECT_EQ(load_all(r), "");
  EXPECT_EQ(r.calibration[2].theta_gain, -0.0019);
}

// Which of two entries for one whisker was meant cannot be known: the later silently won before.
TEST_F(WhiskerdDropins, AWhiskerGivenTwiceInOneFileIsRefused) {
  write("whiskerd.d/20-rest.yaml", "calibration:\n  whiskers:\n    - {index: 3, offset_x: 12.5}\n"
                                   "    - {index: 4, offset_x: 1}\n    - {index: 3, offset_x: -2}\n");
  Params p;
  const std::string error = load_all(p);
  EXPECT_NE(error.find("20-rest.yaml: 'calibration.whiskers[2].index' = 3: whisker 3 has an entry already "
                       "(calibration.whiskers[0])"),
            std::string::npos)
      << error;
  // Two files may: the later one wins (that is how a drop-in corrects another).
  write("whiskerd.d/20-rest.yaml", "calibration:\n  whiskers:\n    - {index: 3, offset_x: 12.5}\n");
  write("whiskerd.d/21-rest.yaml", "calibration:\n  whiskers:\n    - {index: 3, offset_x: -2}\n");
  Params q;
  ASSERT_EQ(load_all(q), "");
  EXPECT_EQ(q.calibration[3].offset_x, -2);
}

// YAML reads 0x10 as 16 (and yaml-cpp 010 as 8): a whisker is numbered in decimal.
TEST_F(WhiskerdDropins, AWhiskerIndexOrChannelNotWrittenInDecimalIsRefused) {
  const std::pair<const char*, const char*> bad[] = {{"index: 0x10", "'calibration.whiskers[0].index' = 0x10 must be 0..23, written in decimal"},
                                                     {"index: 010", "'calibration.whiskers[0].index' = '010'"},
                                                     {"index: 24", "'calibration.whiskers[0].index' = 24 must be 0..23"},
                                                     {"index: -1", "'calibration.whiskers[0].index' = -1 must be 0..23"},
                                                     {"index: 5, channel: 0x6", "'calibration.whiskers[0].channel' = 0x6 must be 0..23, written in decimal"}};
  for (const auto& [entry, why] : bad) expect_refused("10-map.yaml", entry, why);
  write("whiskerd.d/10-map.yaml", "calibration:\n  whiskers:\n    - {index: 0, channel: 0}\n    - {index: 23, offset_x: 2}\n");
  Params q;
  EXPECT_EQ(load_all(q), "");
  EXPECT_EQ(q.calibration[23].offset_x, 2);
}

TEST_F(WhiskerdDropins, SwappedChannelsAreTakenAndAChannelWiredTwiceIsRefused) {
  write("whiskerd.d/10-map.yaml", "calibration:\n  whiskers:\n    - {index: 5, channel: 6}\n    - {index: 6, channel: 5}\n");
  Params p;
  ASSERT_EQ(load_all(p), "");
  EXPECT_EQ(p.channel[5], 6);
  EXPECT_EQ(p.channel[6], 5);
  EXPECT_EQ(p.channel[7], 7);
  write("whiskerd.d/20-bad.yaml", "calibration:\n  whiskers:\n    - {index: 7, channel: 5}\n");
  Params q;
  const std::string error = load_all(q);
  EXPECT_NE(error.find("20-bad.yaml: 'calibration.whiskers' wires channel 5 to whiskers 6 and 7"), std::string::npos)
      << error;
}

TEST_F(WhiskerdDropins, NoConfigFileMeansNoDropins) {
  write("whiskerd.d/20-rest.yaml", "calibration:\n  whiskers:\n    - {index: 3, offset_x: 12.5}\n");
  Params p;
  load_with_dropins(ParamNode::empty(), "", p);
  EXPECT_EQ(p.calibration[3].offset_x, 0.0);
}

TEST_F(WhiskerdDropins, AWrittenDropinLoadsBackTheSameValues) {
  const std::vector<CalibrationEntry> entries = {{3, {{"offset_x", 12.345678901234}, {"gain_y", -0.00051234567}}},
                                                 {5, {{"channel", 6}, {"rotation", -0.1}}},
                                                 {6, {{"channel", 5}}}};
  write("whiskerd.d/20-written.yaml", format_dropin(entries, "written by a test\non two lines"));
  Params p;
  ASSERT_EQ(load_all(p), "");
  EXPECT_EQ(p.calibration[3].offset_x, 12.345678901234);
  EXPECT_EQ(p.calibration[3].gain_y, -0.00051234567);
  EXPECT_EQ(p.calibration[5].rotation, -0.1);
  EXPECT_EQ(p.channel[5], 6);
  EXPECT_EQ(p.channel[6], 5);
}

// The drop-in directory there but not one whiskerd can list: a ParamError naming it (exit 2, one line,
// no restart), where a symbolic link loop or an unreadable directory was a std::filesystem error
// ("filesystem error: ...", exit 1: systemd restarted it for ever) and a link to nothing or a file
// named whiskerd.d left the calibration out without a word.
TEST_F(WhiskerdDropins, ADropinDirectoryThatCannotBeListedIsRefusedNamingIt) {
  const std::filesystem::path d = dir_ / "whiskerd.d";
  std::filesystem::remove_all(d);
  const auto refused = [&](const std::string& what) {
    Params p;
    std::string error;
    EXPECT_NO_THROW(error = load_all(p)) << what;
    EXPECT_EQ(error, d.string() + ": " + what);
  };
  std::filesystem::create_symlink(d, d);  // a loop
  refused("the drop-in directory cannot be read: Too many levels of symbolic links");
  std::filesystem::remove(d);
  std::filesystem::create_symlink(dir_ / "calibration", d);
  refused("the drop-in directory is a symbolic link to " + (dir_ / "calibration").string() + ", which does not exist");
  std::filesystem::remove(d);
  std::filesystem::create_symlink(dir_ / "whiskerd.yaml" / "sub", d);  // a path component that is a file
  refused("the drop-in directory is a symbolic link to " + (dir_ / "whiskerd.yaml" / "sub").string() +
          ", which does not exist");
  std::filesystem::remove(d);
  write("whiskerd.d", "calibration: {}\n");
  refused("the drop-in directory is not a directory (whiskerd reads its *.yaml files; remove it if none)");
  std::filesystem::remove(d);
  Params p;
  EXPECT_EQ(load_all(p), "");  // absent: no drop-ins
}

TEST_F(WhiskerdDropins, ADropinThatIsALinkLoopIsRefusedNamingIt) {
  const std::filesystem::path f = dir_ / "whiskerd.d" / "20-rest.yaml";
  std::filesystem::create_symlink(f, f);
  Params p;
  std::string error;
  EXPECT_NO_THROW(error = load_all(p));
  EXPECT_EQ(error, f.string() + ": a drop-in that cannot be read: Too many levels of symbolic links");
}

// whiskerd runs as its own user (systemd's User=whiskeye): a drop-in directory it may not read. The
// test is root in CI, which reads any directory, so the load runs in a child that has dropped to
// nobody (65534); not root, the test's own user is refused the same.
TEST_F(WhiskerdDropins, ADropinDirectoryItMayNotReadIsRefusedNamingIt) {
  const std::filesystem::path d = dir_ / "whiskerd.d";
  std::filesystem::permissions(dir_, std::filesystem::perms::owner_all | std::filesystem::perms::group_read |
                                         std::filesystem::perms::group_exec | std::filesystem::perms::others_read |
                                         std::filesystem::perms::others_exec);
  std::filesystem::permissions(dir_ / "whiskerd.yaml", std::filesystem::perms::owner_read |
                                                           std::filesystem::perms::owner_write |
                                                           std::filesystem::perms::others_read);
  std::filesystem::permissions(d, std::filesystem::perms::none);
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(fds[0]);
    if (geteuid() == 0 && (setgroups(0, nullptr) != 0 || setgid(65534) != 0 || setuid(65534) != 0)) _exit(3);
    std::string error;
    try {
      Params p;
      error = load_all(p);
    } catch (const std::exception& e) {
      error = std::string("not a ParamError: ") + e.what();
    }
    const ssize_t n = ::write(fds[1], error.data(), error.size());
    _exit(n == static_cast<ssize_t>(error.size()) ? 0 : 4);
  }
  close(fds[1]);
  std::string error;
  char buf[512];
  for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) > 0;) error.append(buf, static_cast<std::size_t>(n));
  close(fds[0]);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  std::filesystem::permissions(d, std::filesystem::perms::owner_all);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  EXPECT_EQ(error, d.string() + ": the drop-in directory cannot be read: Permission denied");
}
