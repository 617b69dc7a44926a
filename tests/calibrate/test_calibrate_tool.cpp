// whiskeye-calibrate end to end, as on the first day with a robot: vita-sim writes the bring-up
// sessions of a robot with a drawn true calibration as candump logs, the tool writes its drop-ins in
// whiskerd's drop-in directory (map, rest, gain, theta), whiskerd's loader reads them, and whiskerd's
// core fed with that robot's frames reproduces the simulated θ and deflections. Bad input through the
// binary: a silent board, a stuck sensor, a sweep interrupted by a fault, a drop-in with a typo.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bringup_rig.h"
#include "private_tmpfs.h"
#include "scratch.h"
#include "subprocess.h"
#include "whiskeye/can/candump.h"
#include "whiskeye/whiskerd/config.h"
#include "whiskeye/whiskerd/whiskerd_core.h"

using namespace whiskeye;
using ::testing::HasSubstr;
using ::testing::Not;
using whiskeye::testing::Subprocess;

namespace {

constexpr uint64_t kTrueSeed = 7;

std::pair<int, std::string> run(std::vector<std::string> args) {
  Subprocess p(args);
  const int status = p.wait(120);
  return {status, p.output()};
}

std::size_t lines(const std::string& text) { return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')); }

class CalibrateTool : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(whiskeye::testing::scratch_dir("calibrate_tool"));
    std::filesystem::create_directories(etc() + "/whiskerd.d");
    std::filesystem::copy_file(WHISKEYE_SOURCE_DIR "/config/whiskerd.yaml", config());
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string etc() { return *dir_ + "/etc"; }
  static std::string config() { return etc() + "/whiskerd.yaml"; }
  static std::string path(const std::string& name) { return *dir_ + "/" + name; }

  // vita-sim --bringup SESSION of the true robot into <name>.log; extra options after.
  static std::string simulate(const std::string& session, const std::string& name, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {VITA_SIM_EXE, "--bringup", session, "--true-calibration-seed",
                                     std::to_string(kTrueSeed), "--whiskerd-config", WHISKEYE_SOURCE_DIR "/config/whiskerd.yaml",
                                     "--candump", path(name + ".log"), "--write-true-calibration", path("truth.yaml")};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto [status, out] = run(args);
    EXPECT_EQ(status, 0) << out;
    return path(name + ".log");
  }
  // whiskeye-calibrate SUBCOMMAND --input LOG -c etc/whiskerd.yaml [args...]
  static std::pair<int, std::string> calibrate(const std::string& sub, const std::string& log, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {CALIBRATE_EXE, sub, "--input", log, "-c", config()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run(args);
  }

  static std::string* dir_;
};
std::string* CalibrateTool::dir_ = nullptr;

TEST_F(CalibrateTool, RecoversTheTrueCalibrationAndWhiskerdReproducesTheSimulatedValues) {
  // The first day: bus check, map, rest, jig, sweep, each writing its drop-in.
  const std::string rest = simulate("rest", "rest");
  const auto [bus_status, bus_out] = run({CALIBRATE_EXE, "bus", "--input", rest, "-c", config()});
  EXPECT_EQ(bus_status, 0) << bus_out;
  EXPECT_THAT(bus_out, HasSubstr("bus: ok"));
  const std::pair<const char*, std::vector<std::string>> steps[] = {
      {"map", {"-o", etc() + "/whiskerd.d/10-map.yaml"}},
      {"rest", {"-o", etc() + "/whiskerd.d/20-rest.yaml"}},
      {"gain", {"--deflection", "0.5", "-o", etc() + "/whiskerd.d/30-gain.yaml"}},
      {"theta", {"-o", etc() + "/whiskerd.d/40-theta.yaml"}}};
  const std::map<std::string, std::string> session_of = {{"map", "taps"}, {"rest", "rest"}, {"gain", "jig"}, {"theta", "sweep"}};
  for (const auto& [sub, args] : steps) {
    const std::string log = sub == std::string("rest") ? rest : simulate(session_of.at(sub), session_of.at(sub));
    const auto [status, out] = calibrate(sub, log, args);
    ASSERT_EQ(status, 0) << sub << ": " << out;
    EXPECT_THAT(out, HasSubstr("whisker  key"));  // the old/new table
  }

  // What whiskerd loads, against the truth (itself a drop-in: load it over the defaults).
  whiskerd::Params loaded;
  whiskerd::load_with_dropins(ParamNode::from_file(config()), config(), loaded);
  whiskerd::CoreParams truth;
  whiskerd::load_dropin(ParamNode::from_file(path("truth.yaml")), truth);
  for (int w = 0; w < kNumWhiskers; ++w) {
    const wp::WhiskerCalibration& t = truth.calibration[static_cast<std::size_t>(w)];
    const wp::WhiskerCalibration& e = loaded.calibration[static_cast<std::size_t>(w)];
    EXPECT_EQ(loaded.channel[static_cast<std::size_t>(w)], truth.channel[static_cast<std::size_t>(w)]) << w;
    EXPECT_NEAR(e.offset_x, t.offset_x, 1.0) << w;
    EXPECT_NEAR(e.offset_y, t.offset_y, 1.0) << w;
    EXPECT_NEAR(e.gain_x / t.gain_x, 1.0, 0.003) << w;
    EXPECT_NEAR(e.gain_y / t.gain_y, 1.0, 0.003) << w;
    EXPECT_NEAR(e.rotation, t.rotation, 0.003) << w;
    EXPECT_NEAR(e.theta_offset, t.theta_offset, 1.0) << w;
    EXPECT_NEAR(e.theta_gain / t.theta_gain, 1.0, 0.002) << w;
  }

  // whiskerd's core with that configuration, fed with the same robot's frames of new sessions (a
  // sweep and a jig on other seeds), reports the simulated θ and deflections.
  const sim::TrueCalibration drawn = sim::draw_true_calibration(kTrueSeed);
  ASSERT_EQ(drawn.channel, truth.channel);
  double worst_theta = 0, worst_deflection = 0;
  int64_t compared = 0;
  for (const sim::Session kind : {sim::Session::kSweep, sim::Session::kJig}) {
    sim::SessionParams p;
    p.session = kind;
    p.seed = 99;
    p.order = {0, 5, 13, drawn.swapped[0], drawn.swapped[1], drawn.mirrored_board * 4 + 2};
    sim::BoardTraffic traffic(calibrate::test::traffic_of(drawn, wp::BusMode::kFd, p.rate_hz));
    whiskerd::WhiskerCore core(loaded);  // each session a fresh start: the boards' sequences start over
    whiskerd::PeriodOutput out;
    std::vector<sim::CanFrame> frames;
    int64_t mono = 0;
    sim::run_session(p, [&](const rcp::WhiskerSample& s, const sim::WhiskerHealth& h) {
      frames.clear();
      traffic.add(s, h, frames);
      mono += 2000;
      for (const sim::CanFrame& f : frames) core.on_frame(f.id, f.fd, f.data, mono);
      core.step(s.utime, mono, out);
      for (int w = 0; w < kNumWhiskers; ++w) {
        worst_theta = std::max(worst_theta, std::abs(out.theta[w] - s.theta[w]));
        worst_deflection = std::max(worst_deflection, std::hypot(out.deflection_x[w] - s.deflection_x[w],
                                                                 out.deflection_y[w] - s.deflection_y[w]));
      }
      ++compared;
    });
  }
  EXPECT_GT(compared, 10000);
  EXPECT_LT(worst_theta, 0.003) << "rad";
  EXPECT_LT(worst_deflection, 0.004) << "full scale";
  std::cout << "whiskerd with the drop-ins: worst theta error " << worst_theta << " rad, worst deflection error "
            << worst_deflection << " over " << compared << " periods\n";
}

TEST_F(CalibrateTool, ASilentBoardFailsTheBusCheckAndRestWritesNothing) {
  const std::string log = simulate("rest", "silent", {"--silent-board", "3", "--bringup-duration", "2"});
  const auto [bus_status, bus_out] = calibrate("bus", log);
  EXPECT_EQ(bus_status, 1) << bus_out;
  EXPECT_THAT(bus_out, HasSubstr("    3     4        0.0           0.0     0  FAIL: absent"));
  const std::string dropin = path("silent-rest.yaml");
  const auto [status, out] = calibrate("rest", log, {"-o", dropin});
  EXPECT_EQ(status, 1) << out;
  EXPECT_THAT(out, HasSubstr("whiskeye-calibrate: rest: board 3 (CAN node 4) sent no samples"));
  EXPECT_FALSE(std::filesystem::exists(dropin));
}

TEST_F(CalibrateTool, AStuckSensorIsOneLineNamingTheWhisker) {
  const std::string log = simulate("rest", "stuck", {"--stuck-whiskers", "14", "--bringup-duration", "2"});
  const auto [status, out] = calibrate("rest", log, {"-o", path("stuck-rest.yaml")});
  EXPECT_EQ(status, 1) << out;
  EXPECT_THAT(out, HasSubstr("whiskeye-calibrate: rest: whisker 14 (row 2, column 2)"));
  EXPECT_THAT(out, HasSubstr("stuck"));
  EXPECT_FALSE(std::filesystem::exists(path("stuck-rest.yaml")));
}

TEST_F(CalibrateTool, ASweepInterruptedByAFaultIsRefused) {
  const std::string log = simulate("sweep", "fault", {"--fault-at", "3"});
  const auto [status, out] = calibrate("theta", log, {"-o", path("fault-theta.yaml")});
  EXPECT_EQ(status, 1) << out;
  EXPECT_THAT(out, HasSubstr("whiskeye-calibrate: theta: sweep interrupted by a fault: board 0 reports a fault from 3.00 s"));
  EXPECT_FALSE(std::filesystem::exists(path("fault-theta.yaml")));
}

TEST_F(CalibrateTool, ADropinWithATypoIsOneLineNamingTheFileAndTheKey) {
  const std::string typo_etc = path("typo");
  std::filesystem::create_directories(typo_etc + "/whiskerd.d");
  std::filesystem::copy_file(WHISKEYE_SOURCE_DIR "/config/whiskerd.yaml", typo_etc + "/whiskerd.yaml");
  const std::string typo = typo_etc + "/whiskerd.d/20-rest.yaml";
  std::ofstream(typo) << "calibration:\n  whiskers:\n    - {index: 2, ofset_x: 3.5}\n";
  const std::string log = simulate("rest", "typo", {"--bringup-duration", "1"});
  const auto [status, out] = run({CALIBRATE_EXE, "rest", "--input", log, "-c", typo_etc + "/whiskerd.yaml"});
  EXPECT_EQ(status, 2) << out;
  EXPECT_EQ(lines(out), 1u) << out;
  EXPECT_THAT(out, HasSubstr("whiskeye-calibrate: bad config: " + typo + ": unknown key 'calibration.whiskers[0].ofset_x' (line 3)"));
  // whiskerd refuses it the same way, before it opens any device.
  const auto [wstatus, wout] = run({WHISKERD_EXE, "-c", typo_etc + "/whiskerd.yaml", "--print-config"});
  EXPECT_EQ(wstatus, 2) << wout;
  EXPECT_THAT(wout, HasSubstr(typo + ": unknown key 'calibration.whiskers[0].ofset_x'"));
}

// On a full disk the drop-in whiskerd loads stays as it was (it became a 0-byte file whiskerd loaded
// with exit 0); with room again the same run replaces it whole.
TEST_F(CalibrateTool, OnAFullDiskTheDropinInUseStaysWholeAndNothingElseIsLeft) {
  // Before any child process (unshare refuses a process with threads; a fork is none).
  whiskeye::testing::PrivateTmpfs disk(path("full_etc"), "256k");
  ASSERT_TRUE(disk.mounted()) << disk.error();
  const std::string etc = disk.dir(), cfg = etc + "/whiskerd.yaml", dropin = etc + "/whiskerd.d/20-rest.yaml";
  std::filesystem::create_directories(etc + "/whiskerd.d");
  std::filesystem::copy_file(WHISKEYE_SOURCE_DIR "/config/whiskerd.yaml", cfg);
  const std::string log = simulate("rest", "full_rest", {"--bringup-duration", "1"});
  const auto [first, first_out] = run({CALIBRATE_EXE, "rest", "--input", log, "-c", cfg, "-o", dropin});
  ASSERT_EQ(first, 0) << first_out;
  std::ifstream in(dropin);
  const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(good.size(), 1000u);

  ASSERT_GT(whiskeye::testing::fill_disk(etc + "/filler"), 0u);
  const auto [status, out] = run({CALIBRATE_EXE, "rest", "--input", log, "-c", cfg, "-o", dropin});
  EXPECT_EQ(status, 1) << out;
  EXPECT_THAT(out, HasSubstr("whiskeye-calibrate: " + dropin + ": cannot write: No space left on device\n"));
  EXPECT_THAT(out, Not(HasSubstr("wrote")));
  std::ifstream after_in(dropin);
  const std::string after((std::istreambuf_iterator<char>(after_in)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(after == good) << "the drop-in in use is now " << after.size() << " bytes, was " << good.size();
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(etc + "/whiskerd.d"), {}), 1) << "a temp file was left";
  whiskerd::Params loaded;
  EXPECT_THAT(whiskerd::load_with_dropins(ParamNode::from_file(cfg), cfg, loaded), HasSubstr("# drop-in " + dropin));

  std::filesystem::remove(etc + "/filler");
  const auto [again, again_out] = run({CALIBRATE_EXE, "rest", "--input", log, "-c", cfg, "-o", dropin});
  EXPECT_EQ(again, 0) << again_out;
  EXPECT_THAT(again_out, HasSubstr("rest: wrote " + dropin));
}

// -o that is not a file the drop-in can replace, or is a file the tool reads: one line, exit 2, before
// the log is read or the bus listened to, and the file left as it was. A FIFO blocked the tool for
// ever; a symbolic link was followed.
TEST_F(CalibrateTool, AnOutputThatCannotBeReplacedOrIsAnInputIsRefusedBeforeAnythingIsRead) {
  namespace fs = std::filesystem;
  const std::string log = simulate("rest", "refused_rest", {"--bringup-duration", "1"});
  const std::string d = path("refused");
  fs::create_directories(d);
  ASSERT_EQ(::mkfifo((d + "/fifo.yaml").c_str(), 0644), 0);
  std::ofstream(d + "/elsewhere") << "kept";
  fs::create_symlink(d + "/elsewhere", d + "/link.yaml");
  fs::create_hard_link(log, d + "/hard.log");
  const std::pair<std::string, std::string> cases[] = {
      {d + "/fifo.yaml", ": is a FIFO, not a regular file"},
      {d + "/link.yaml", ": is a symbolic link (to " + d + "/elsewhere), not followed: give the file itself"},
      {d, ": is a directory, not a regular file"},
      {d + "/missing/20-rest.yaml", ": its directory " + d + "/missing cannot be used: No such file or directory"},
      {log, " is the file given to --input (" + log + "): writing it would destroy it"},
      {d + "/hard.log", " is the file given to --input (" + log + "): writing it would destroy it"},
      {config(), " is the file given to --config (" + config() + "): writing it would destroy it"},
  };
  const std::string log_before = std::to_string(fs::file_size(log));
  for (const auto& [out, why] : cases) {
    Subprocess p({CALIBRATE_EXE, "rest", "--input", log, "-c", config(), "-o", out});
    EXPECT_EQ(p.wait(20), 2) << out << ": " << p.output();
    EXPECT_EQ(p.output(), "whiskeye-calibrate: -o " + out + why + "\n");
  }
  EXPECT_TRUE(fs::is_fifo(d + "/fifo.yaml"));
  EXPECT_TRUE(fs::is_symlink(d + "/link.yaml"));
  std::ifstream kept(d + "/elsewhere");
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(kept)), std::istreambuf_iterator<char>()), "kept");
  EXPECT_EQ(std::to_string(fs::file_size(log)), log_before);
  EXPECT_FALSE(fs::exists(d + "/missing"));
}

// whiskerd reads whiskerd.d/NAME.yaml only: a 20-rest.yml, or -o whiskerd.d itself with the directory
// missing (a *file* named whiskerd.d was created), was written, "wrote", exit 0, and never loaded.
TEST_F(CalibrateTool, AnOutputWhiskerdWouldNotReadIsRefusedBeforeAnythingIsRead) {
  namespace fs = std::filesystem;
  const std::string log = simulate("rest", "unread_rest", {"--bringup-duration", "1"});
  const std::string d = path("unread");
  fs::create_directories(d);
  fs::copy_file(config(), d + "/whiskerd.yaml");
  for (const std::string& out : {d + "/whiskerd.d", etc() + "/whiskerd.d/20-rest.yml", etc() + "/whiskerd.d/20-rest"}) {
    Subprocess p({CALIBRATE_EXE, "rest", "--input", log, "-c", d + "/whiskerd.yaml", "-o", out});
    EXPECT_EQ(p.wait(20), 2) << out << ": " << p.output();
    EXPECT_EQ(p.output(), "whiskeye-calibrate: -o " + out + ": whiskerd would not read it: its drop-ins are NAME.yaml files in " +
                              d + "/whiskerd.d/ (e.g. 20-rest.yaml)\n");
    EXPECT_FALSE(fs::exists(out)) << out;
  }
}

// A candump log is a regular file, read a line of at most 512 bytes at a time: /dev/zero and a 2 GB
// sparse file (one endless line of NULs) took 2.1 GB, then said "no CAN frame in the log"; a FIFO
// blocked in open(). Here under a 512 MB address-space limit.
TEST_F(CalibrateTool, ALogThatIsNoRegularFileOrAnEndlessLineIsRefusedAtOnceInBoundedMemory) {
  namespace fs = std::filesystem;
  const std::string fifo = path("fifo.log"), sparse = path("sparse.log");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  std::ofstream(sparse).close();
  fs::resize_file(sparse, uint64_t{2} << 30);  // sparse: no block written
  const std::pair<std::string, std::string> cases[] = {
      {fifo, fifo + ": cannot open the candump log for reading: not a regular file"},
      {"/dev/zero", "/dev/zero: cannot open the candump log for reading: not a regular file"},
      {"/proc/self/status", "/proc/self/status: cannot open the candump log for reading: not a regular file (it reports 0 bytes but holds data)"},
      {sparse, sparse + ":1: not a candump -l line: longer than 512 bytes"}};
  for (const auto& [input, why] : cases) {
    Subprocess p({"bash", "-c", "ulimit -v 524288 && exec \"$0\" \"$@\"", CALIBRATE_EXE, "bus", "--input", input, "-c", config()});
    EXPECT_EQ(p.wait(20), 1) << input << ": " << p.output();
    EXPECT_EQ(p.output(), "whiskeye-calibrate: " + why + "\n");
  }
  fs::remove(sparse);
}

// The bus check through the binary on logs a real day makes: CRLF line ends, extended-id and remote
// frames between the whiskers' (live listening skips them: the log was refused), two sessions one
// after the other, a frame 30 years late. Every board at its 500 Hz: the span was the first line's
// time to the last's (0.0 Hz for every board). A log reversed spans what it does forwards
// (CalibrateBus.TheSpanIsTheTimeBetweenFramesWhateverTheirOrder), but fails here: the assembler takes
// every sample whose sequence number steps back for an old one.
TEST_F(CalibrateTool, TheBusCheckRatesEveryBoardWhateverTheLogsOrderLineEndsAndForeignFrames) {
  const std::string rest = simulate("rest", "order_rest", {"--bringup-duration", "2"});
  std::vector<std::string> lines;
  std::ifstream in(rest);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_GT(lines.size(), 1000u);
  const auto shifted = [](const std::string& line, int64_t by_us) {
    can::LoggedFrame f;
    std::string interface;
    EXPECT_TRUE(can::parse_candump_line(line, f, interface)) << line;
    f.utime += by_us;
    return can::format_candump_line(f, interface);
  };
  std::map<std::string, std::vector<std::string>> logs;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    logs["crlf"].push_back(lines[i] + "\r");
    logs["foreign"].push_back(lines[i]);
    if (i % 50 == 0) {
      const std::string stamp = lines[i].substr(0, lines[i].find(' '));
      logs["foreign"].push_back(stamp + " can0 1ABCDEF0#0011");
      logs["foreign"].push_back(stamp + " can0 123#R");
      logs["foreign"].push_back(stamp + " can0 00000702#R8");
    }
    logs["wild"].push_back(i == lines.size() / 2 ? shifted(lines[i], int64_t{30} * 365 * 86400 * 1000000) : lines[i]);
  }
  logs["sessions"] = lines;
  for (const std::string& line : lines) logs["sessions"].push_back(shifted(line, -int64_t{86400} * 1000000));
  for (const auto& [name, log] : logs) {
    const std::string file = path("order_" + name + ".log");
    std::ofstream out(file);
    for (const std::string& line : log) out << line << "\n";
    out.close();
    const auto [status, report] = run({CALIBRATE_EXE, "bus", "--input", file, "-c", config()});
    EXPECT_EQ(status, 0) << name << ": " << report;
    std::istringstream rows(report.substr(report.find('\n') + 1));
    for (int b = 0; b < wp::kNumBoards; ++b) {
      int board = -1, node = -1;
      double samples_hz = 0;
      rows >> board >> node >> samples_hz;
      rows.ignore(1000, '\n');
      EXPECT_EQ(board, b) << name << ": " << report;
      EXPECT_NEAR(samples_hz, 500.0, 1.0) << name << ": board " << b;  // 2 s of samples over 2 s
    }
    EXPECT_THAT(report, HasSubstr("bus: ok")) << name;
  }
}

TEST_F(CalibrateTool, ALogThatIsNotACandumpIsOneLineNamingTheLine) {
  const std::string bad = path("bad.log");
  std::ofstream(bad) << "(1700000000.000000) can0 701#05\nhello\n";
  const auto [status, out] = calibrate("bus", bad);
  EXPECT_EQ(status, 1) << out;
  EXPECT_EQ(lines(out), 1u) << out;
  EXPECT_THAT(out, HasSubstr(bad + ":2: not a candump -l line: 'hello'"));
}

TEST_F(CalibrateTool, ALiveSweepWithoutItsDevicesIsOneLineNamingThemAndMovesNothing) {
  // theta on the bus opens the motor lines first, then the CAN interface: either missing is exit 1.
  const auto [status, out] = run({CALIBRATE_EXE, "theta", "-c", config(), "-i", "nosuchcan0"});
  EXPECT_EQ(status, 1) << out;
  EXPECT_EQ(lines(out), 1u) << out;
  EXPECT_THAT(out, HasSubstr("whiskeye-calibrate: GPIO line 'WHISKER_MOTOR_EN'"));
  const auto [can_status, can_out] = run({CALIBRATE_EXE, "theta", "-c", config(), "-i", "nosuchcan0", "--no-gpio"});
  EXPECT_EQ(can_status, 1) << can_out;
  EXPECT_EQ(lines(can_out), 1u) << can_out;
  EXPECT_THAT(can_out, HasSubstr("whiskeye-calibrate: CAN nosuchcan0: "));
}

}  // namespace

namespace {

TEST(VitaSimBringup, BadOptionsAreOneLineAndExit2) {
  const std::vector<std::vector<std::string>> bad = {
      {VITA_SIM_EXE, "--bringup", "rest"},                                          // no --candump
      {VITA_SIM_EXE, "--bringup", "nap", "--candump", "/dev/null"},                 // no such session
      {VITA_SIM_EXE, "--bringup", "rest", "--candump", "/dev/null", "--silent-board", "6"}};
  for (const auto& args : bad) {
    const auto [status, out] = run(args);
    EXPECT_EQ(status, 2) << out;
    EXPECT_EQ(lines(out), 1u) << out;
    EXPECT_EQ(out.rfind("vita-sim: ", 0), 0u) << out;
  }
}

}  // namespace
