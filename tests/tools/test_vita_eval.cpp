// Integration test of the vita-eval binary: writes small slamd-like output logs (VITA_* and
// GROUND_TRUTH) with LogWriterBus, runs the real executable on them and checks its JSON, its table
// and its PNG and SVG plots; and, on a short vita-sim + slamd --replay run with GROUND_TRUTH filtered
// out (a real robot's log), that it draws the run over the world and reports what needs truth as
// unavailable.
#include "scratch.h"
#include "subprocess.h"
#include "whiskeye/common/bus.h"
#include "whiskeye/common/se2.h"

#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/sim_fault_t.hpp>
#include <whiskeye/template_match_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include <sys/stat.h>
#include <sys/wait.h>

namespace whiskeye {
namespace {

constexpr int64_t kSecond = 1'000'000;
constexpr int64_t kStart = 1'700'000'000 * kSecond;  // a realistic epoch time
constexpr double kPeriodS = 20.0;                    // one revolution
const Pose2 kWorldMap{0.5, -0.2, 0.3};               // where slamd's map frame sits in the world

Pose2 gt_at(int64_t utime) {
  const double a = kTwoPi * static_cast<double>(utime - kStart) / (kPeriodS * kSecond);
  return {std::cos(a), std::sin(a), wrap_angle(a)};  // 1 m circle, facing outwards
}

Pose2 map_pose(int64_t utime) { return compose(inverse(kWorldMap), gt_at(utime)); }

experience_t experience(int32_t id, int64_t utime, double heading_error = 0.0) {
  experience_t e{};
  const Pose2 p = map_pose(utime);
  e.id = id;
  e.x = p.x;
  e.y = p.y;
  e.theta = wrap_angle(p.theta + heading_error);
  e.utime_created = utime;
  e.visual_template_id = id;
  e.tactile_template_id = id % 2 == 0 ? id : -1;
  e.dense = id % 2 == 0;
  return e;
}

// pose2d_t and vita_pose_t share these fields.
template <typename Msg>
void set_pose(Msg& msg, int64_t utime, const Pose2& p) {
  msg.utime = utime;
  msg.x = p.x;
  msg.y = p.y;
  msg.theta = p.theta;
}

link_t link(int32_t from, int32_t to) {
  link_t l{};
  l.from_id = from;
  l.to_id = to;
  return l;
}

struct Script {
  int8_t mode = vita_pose_t::MODE_VITA;
  bool relocalise = true;  // false: new experiences all through the second revolution instead
  int64_t pose_delay_us = 0;  // VITA_POSE stamped this much later (past the ground truth: no LEM)
  bool board_fault = false;   // SIM_FAULT: board 2 offline from 10 s to 25 s
  bool ground_truth = true;   // false: no GROUND_TRUTH (a real robot's log)
  // The re-localisation of 35 s made 0.3 s later (0.094 m and 5.4 deg past where experience 15 was
  // made): wrong by the paper's thresholds, within the false-closure tolerance.
  bool neighbour_miss = false;
  // A kidnap at 25 s half a revolution ahead (SIM_FAULT, GROUND_TRUTH jumps): slamd stays on its
  // experience reporting LOCALISING until 28 s, re-localises correctly at 28 and 29 s, falsely onto
  // experience 3 at 30 s, and correctly from 31 s on.
  bool kidnap = false;
  // A second session: every time 1000 s (50 revolutions) later, the final map's experiences created
  // in the first session (1000 s earlier).
  bool second_session = false;
};

// Two revolutions. Experiences 0..19 are created once a second in the first; in the second the
// robot re-localises to the experience of the same place each second (correct), except at 30 s it
// jumps to experience 3 (incorrect), creates experience 20 at 30.5 s (invalid, heading off by
// 0.2 rad in the map) and re-localises correctly again at 31 s.
// Expected: ARR = 19/20, ARCR = 18/19, valid 20/21, LEM 0, EnM = 0.2² / 20 links; the wrong one a
// false closure 1.78 m off; experiences 18 deg (0.3129 m) apart.
void write_log(const std::string& path, const Script& script) {
  const int64_t start = kStart + (script.second_session ? 1000 * kSecond : 0);
  const auto truth = [&](int64_t t) { return script.kidnap && t >= start + 25 * kSecond ? gt_at(t + 10 * kSecond) : gt_at(t); };
  const auto localising = [&](int64_t t) {
    return script.kidnap && t >= start + 25 * kSecond && t < start + 28 * kSecond;
  };
  LogWriterBus bus(path);
  vita_map_t map{};
  map.mode = script.mode;
  int32_t current = -1;
  auto publish_event = [&](int64_t t, int8_t type, int32_t to) {
    vita_event_t e{};
    e.utime = t;
    e.cycle = (t - start) / (kSecond / 2);
    e.type = type;
    e.from_id = current;
    e.to_id = to;
    e.mode = script.mode;
    e.localisation = localising(t) ? vita_pose_t::LOCALISATION_LOCALISING : vita_pose_t::LOCALISATION_TRACKING;
    bus.set_time(t);
    publish(bus, "VITA_EVENT", e);
    template_match_t m{};  // the cycle's match: the target's template, new with a new experience
    m.utime = t;
    m.cycle = e.cycle;
    m.template_id = to;
    m.is_new = type == vita_event_t::NEW_EXPERIENCE;
    m.error = m.visual_error = 0.01 * to;
    m.visual_shift = to % 5 - 2;
    m.mode = script.mode;
    m.visual_used = true;
    publish(bus, "VITA_MATCH", m);
    current = to;
  };
  auto add_experience = [&](int64_t t, int32_t id, double heading_error = 0.0) {
    if (current >= 0) map.links.push_back(link(current, id));
    map.experiences.push_back(experience(id, t, heading_error));
    publish_event(t, vita_event_t::NEW_EXPERIENCE, id);
  };
  for (int64_t u = 0; u <= static_cast<int64_t>(2 * kPeriodS) * kSecond; u += 20'000) {  // 50 Hz
    const int64_t t = start + u;
    bus.set_time(t);
    pose2d_t gt{};
    set_pose(gt, t, truth(t));
    if (script.ground_truth) publish(bus, "GROUND_TRUTH", gt);
    if (u % 100'000 == 0) {  // 10 Hz pose estimate, exact in the map frame
      vita_pose_t vp{};
      set_pose(vp, t + script.pose_delay_us, map_pose(t));
      vp.experience_id = current;
      vp.mode = script.mode;
      vp.localisation = localising(t) ? vita_pose_t::LOCALISATION_LOCALISING : vita_pose_t::LOCALISATION_TRACKING;
      publish(bus, "VITA_POSE", vp);
    }
    if (script.kidnap && u == 25 * kSecond) {
      sim_fault_t f{};
      f.utime = t;
      f.kind = sim_fault_t::KIND_KIDNAP;
      f.active = true;
      f.index = -1;
      set_pose(f, t, truth(t));
      publish(bus, "SIM_FAULT", f);
    }
    if (u % kSecond == 0 && script.board_fault && (u == 10 * kSecond || u == 25 * kSecond)) {
      sim_fault_t f{};
      f.utime = t;
      f.kind = sim_fault_t::KIND_BOARD_OFFLINE;
      f.active = u == 10 * kSecond;
      f.index = 2;
      publish(bus, "SIM_FAULT", f);
    }
    if (u % kSecond == 0) {
      const int64_t s = u / kSecond;
      if (s < 20) {
        add_experience(t, static_cast<int32_t>(s));
      } else if (s == 35 && script.relocalise && script.neighbour_miss) {
        // published 0.3 s later, below
      } else if (script.kidnap && (s == 26 || s == 27)) {
        publish_event(t, vita_event_t::SAME_EXPERIENCE, current);
      } else if (s > 20 && s < 40 && script.relocalise) {
        const int64_t place = script.kidnap && s > 25 ? (s + 10) % 20 : s - 20;  // where the robot is
        publish_event(t, vita_event_t::RELOCALISE, s == 30 ? 3 : static_cast<int32_t>(place));
      } else if (s > 20 && s < 40) {
        add_experience(t, static_cast<int32_t>(s + 100));  // never recognises a place: no loop closure
      } else if (s == 40 && !script.kidnap && !script.second_session) {  // 0.31 m past where 19 was made
        publish_event(t, vita_event_t::SAME_EXPERIENCE, current);
      }
      if (s == 10) {  // an early, partial map that must not be the one evaluated
        vita_map_t early = map;
        early.experiences[0].x += 5.0;
        early.num_experiences = static_cast<int32_t>(early.experiences.size());
        early.num_links = static_cast<int32_t>(early.links.size());
        publish(bus, "VITA_MAP", early);
      }
    }
    if (u == 30 * kSecond + kSecond / 2 && script.relocalise) add_experience(t, 20, 0.2);
    if (u == 35 * kSecond + 300'000 && script.relocalise && script.neighbour_miss) {
      publish_event(t, vita_event_t::RELOCALISE, 15);
    }
    if (u == 0) publish(bus, "SOMETHING_ELSE", gt);  // other channels are ignored
  }
  map.utime = start + static_cast<int64_t>(2 * kPeriodS) * kSecond;
  map.num_experiences = static_cast<int32_t>(map.experiences.size());
  map.num_links = static_cast<int32_t>(map.links.size());
  map.current_experience_id = current;
  if (script.second_session) {
    for (experience_t& e : map.experiences) e.utime_created -= 1000 * kSecond;
  }
  bus.set_time(map.utime);
  publish(bus, "VITA_MAP", map);
}

int run_vita_eval(const std::string& args, const std::string& stdout_path) {
  const std::string cmd = std::string(VITA_EVAL_BINARY) + " " + args + " > " + stdout_path + " 2>&1";
  return std::system(cmd.c_str());
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Pixels of roughly this BGR colour.
int count_colour(const cv::Mat& img, int b, int g, int r) {
  int n = 0;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
      if (std::abs(p[0] - b) < 30 && std::abs(p[1] - g) < 30 && std::abs(p[2] - r) < 30) ++n;
    }
  }
  return n;
}

// Occurrences of `needle` in `text`.
int count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

class VitaEvalBinary : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = whiskeye::testing::scratch_dir("vita_eval_" +
                                          std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

TEST_F(VitaEvalBinary, ComputesTheExpectedMetricsAndWritesJsonAndPlots) {
  write_log(file("vita.lcmlog"), Script{});
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + " --json " + file("out.json") + " --plots " +
                              file("plots") + " --paper-row vita",
                          file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));

  const nlohmann::json j = nlohmann::json::parse(read_text(file("out.json")));
  ASSERT_EQ(j["runs"].size(), 1u);
  const nlohmann::json& run = j["runs"][0];
  EXPECT_EQ(run["label"], "vita");
  EXPECT_EQ(run["counts"]["map_experiences"], 21);
  EXPECT_TRUE(run["alignment"]["valid"]);
  EXPECT_NEAR(run["alignment"]["T_world_map"]["x"].get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(run["alignment"]["T_world_map"]["theta"].get<double>(), 0.3, 1e-9);
  EXPECT_LT(run["lem"]["position_m"]["rmse"].get<double>(), 1e-9);
  EXPECT_LT(run["lem"]["orientation_rad"]["rmse"].get<double>(), 1e-9);
  EXPECT_EQ(run["lem"]["samples_used"], 401);
  // ATE: the estimate is exact in the map frame, so the best fit finds the map frame and no error.
  EXPECT_EQ(run["ate"]["samples_used"], 401);
  EXPECT_EQ(run["ate"]["samples_localising"], 0);
  EXPECT_NEAR(run["ate"]["alignment"]["T_world_map"]["x"].get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(run["ate"]["alignment"]["T_world_map"]["y"].get<double>(), -0.2, 1e-9);
  EXPECT_NEAR(run["ate"]["alignment"]["T_world_map"]["theta"].get<double>(), 0.3, 1e-9);
  for (const char* k : {"rmse", "mean", "median", "max"}) EXPECT_LT(run["ate"]["position_m"][k].get<double>(), 1e-9) << k;
  EXPECT_NEAR(run["ate"]["lap_length_m"].get<double>(), kTwoPi, 1e-3);
  ASSERT_EQ(run["ate"]["windows"].size(), 1u) << "two laps make one window of four";
  EXPECT_EQ(run["ate"]["windows"][0]["samples"], 401);
  EXPECT_DOUBLE_EQ(j["params"]["ate_window_laps"].get<double>(), 4.0);
  EXPECT_EQ(run["exm"]["base_set_size"], 20);
  EXPECT_NEAR(run["exm"]["base_end_s"].get<double>(), 20.0, 1e-5);
  EXPECT_EQ(run["exm"]["experience_events_after_base"], 20);
  EXPECT_EQ(run["exm"]["relocalisations_after_base"], 19);
  EXPECT_NEAR(run["exm"]["arr"].get<double>(), 19.0 / 20.0, 1e-12);
  EXPECT_NEAR(run["exm"]["arcr"].get<double>(), 18.0 / 19.0, 1e-12);
  EXPECT_NEAR(run["exm"]["valid_fraction"].get<double>(), 20.0 / 21.0, 1e-12);
  EXPECT_EQ(run["enm"]["links_used"], 20);
  EXPECT_NEAR(run["enm"]["enm"].get<double>(), 0.04 / 20.0, 1e-9);
  EXPECT_NEAR(run["enm"]["rotation_rad2"].get<double>(), 0.04 / 20.0, 1e-9);
  EXPECT_NEAR(run["enm"]["translation_m2"].get<double>(), 0.0, 1e-12);
  // The wrong re-localisation (30 s, to experience 3) is a false closure: the robot at (-1, 0), the
  // target made at (cos 54°, sin 54°).
  const double worst = std::hypot(-1.0 - std::cos(deg_to_rad(54.0)), std::sin(deg_to_rad(54.0)));
  EXPECT_EQ(run["exm"]["false_closures"], 1);
  EXPECT_NEAR(run["exm"]["false_closure_worst_m"].get<double>(), worst, 1e-6);
  EXPECT_EQ(run["exm"]["neighbour_misses"], 0);
  EXPECT_DOUBLE_EQ(run["exm"]["neighbour_miss_share"].get<double>(), 0.0);
  int false_in_list = 0;
  for (const nlohmann::json& r : run["exm"]["relocalisations"]) false_in_list += r["closure"] == "false";
  EXPECT_EQ(false_in_list, 1);
  // Experiences one second apart on the circle: chords of 18 deg; 0->1..18->19 and 3->20.
  EXPECT_EQ(run["exm"]["experience_spacing"]["steps"], 20);
  EXPECT_NEAR(run["exm"]["experience_spacing"]["median_m"].get<double>(), 2.0 * std::sin(deg_to_rad(9.0)), 1e-6);
  EXPECT_NEAR(run["exm"]["experience_spacing"]["median_heading_deg"].get<double>(), 18.0, 1e-4);
  EXPECT_DOUBLE_EQ(j["params"]["false_closure_position_m"].get<double>(), 0.25);
  EXPECT_NEAR(j["params"]["false_closure_angle_rad"].get<double>(), deg_to_rad(15.0), 1e-12);
  ASSERT_EQ(j["paper_rows"].size(), 1u);
  EXPECT_DOUBLE_EQ(j["paper_rows"][0]["enm"].get<double>(), 0.4311);

  const std::string table = read_text(file("stdout.txt"));
  EXPECT_NE(table.find("paper ViTa-SLAM"), std::string::npos);
  EXPECT_NE(table.find("ATE (m)   paper's LEM pos (m)"), std::string::npos) << table;
  EXPECT_NE(table.find("1        0.0000    0.0000 (0.0000"), std::string::npos) << table;  // ATE, then LEM
  EXPECT_NE(table.find("ATE (best-fit SE(2) alignment T_world_map = (0.5000, -0.2000, 0.3000 rad)): RMSE 0.0000 m"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("0.9474   1 "), std::string::npos) << table;  // ARCR 18/19 and one false closure
  EXPECT_NE(table.find("closures"), std::string::npos) << table;
  EXPECT_NE(table.find("1 false closures (target beyond 0.25 m or 15 deg; worst 1.782 m), 0 neighbour misses"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("experience spacing (ground truth, 20 steps to a new experience): median 0.313 m, 18.00 deg"),
            std::string::npos)
      << table;

  const cv::Mat map_png = cv::imread(file("plots/vita_experience_map.png"));
  ASSERT_FALSE(map_png.empty());
  EXPECT_GE(map_png.cols, 600);
  EXPECT_GT(count_colour(map_png, 0, 140, 255), 100);    // dense experiences (orange)
  EXPECT_GT(count_colour(map_png, 170, 170, 170), 500);  // ground-truth trajectory (grey)
  const cv::Mat reloc_png = cv::imread(file("plots/vita_relocalisations.png"));
  ASSERT_FALSE(reloc_png.empty());
  EXPECT_GT(count_colour(reloc_png, 40, 40, 220), 100);  // the false closure (red)
  EXPECT_GT(count_colour(reloc_png, 40, 160, 40), 100);  // correct ones (green)
}

TEST_F(VitaEvalBinary, DrawsAndCountsANeighbourMissApartFromAFalseClosure) {
  Script script;
  script.neighbour_miss = true;
  write_log(file("vita.lcmlog"), script);
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + " --json " + file("out.json") + " --plots " +
                              file("plots") + " --trace " + file("trace"),
                          file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));
  const nlohmann::json exm = nlohmann::json::parse(read_text(file("out.json")))["runs"][0]["exm"];
  EXPECT_EQ(exm["correct_total"], 17);
  EXPECT_EQ(exm["neighbour_misses"], 1);
  EXPECT_EQ(exm["false_closures"], 1);
  EXPECT_DOUBLE_EQ(exm["neighbour_miss_share"].get<double>(), 0.5);
  const std::string svg = read_text(file("plots/vita_relocalisations.svg"));
  EXPECT_EQ(count(svg, "class=\"relocalisation neighbour\""), 1);
  EXPECT_EQ(count(svg, "class=\"relocalisation false\""), 1);
  EXPECT_EQ(count(svg, "class=\"relocalisation correct\""), 17);
  // The legend (wrapped at 44 characters) names the three verdicts, their bounds and counts.
  EXPECT_NE(svg.find(">correct: within 0.08 m and 4.6 deg (17)<"), std::string::npos);
  EXPECT_NE(svg.find(">neighbour miss: wrong, but within 0.25 m and<"), std::string::npos);
  EXPECT_NE(svg.find(">15 deg (1)<"), std::string::npos);
  EXPECT_NE(svg.find(">false closure: beyond 0.25 m or 15 deg (1)<"), std::string::npos);
  // Amber beyond the legend's sample: the same run without the neighbour miss has only that.
  write_log(file("plain.lcmlog"), Script{});
  ASSERT_EQ(run_vita_eval("--input " + file("plain.lcmlog") + " --plots " + file("plain"), file("stdout0.txt")), 0);
  const cv::Mat png = cv::imread(file("plots/vita_relocalisations.png"));
  const cv::Mat plain = cv::imread(file("plain/vita_relocalisations.png"));
  ASSERT_FALSE(png.empty() || plain.empty());
  EXPECT_GT(count_colour(png, 0, 150, 235), count_colour(plain, 0, 150, 235) + 20);  // the neighbour miss (amber)
  EXPECT_GT(count_colour(png, 40, 40, 220), 100);                                    // the false closure (red)
  const std::string trace = read_text(file("trace/vita_trace.csv"));
  const std::size_t row = trace.find(",35.300,relocalise,14,15,");
  ASSERT_NE(row, std::string::npos) << trace;
  EXPECT_NE(trace.substr(row, trace.find('\n', row) - row).find(",0,1,neighbour,"), std::string::npos)
      << "correct 0, after the base set, a neighbour miss";
  // With a tolerance narrower than 0.094 m both wrong ones are false closures.
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + " --json " + file("narrow.json") +
                              " --false-closure-tolerance 0.09,15",
                          file("stdout2.txt")),
            0)
      << read_text(file("stdout2.txt"));
  const nlohmann::json narrow = nlohmann::json::parse(read_text(file("narrow.json")));
  EXPECT_EQ(narrow["runs"][0]["exm"]["false_closures"], 2);
  EXPECT_DOUBLE_EQ(narrow["params"]["false_closure_position_m"].get<double>(), 0.09);
}

TEST_F(VitaEvalBinary, WritesAPerCycleTraceThatAgreesWithTheMetrics) {
  write_log(file("vita.lcmlog"), Script{});
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + " --trace " + file("trace"), file("stdout.txt")), 0)
      << read_text(file("stdout.txt"));
  std::istringstream csv(read_text(file("trace/vita_trace.csv")));
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line.rfind("cycle,t_s,event,from_id,to_id,", 0), 0u) << line;
  EXPECT_NE(line.find(",correct,after_base_set,closure,template_id,"), std::string::npos) << line;
  const auto split = [](const std::string& l) {
    std::vector<std::string> f;
    std::stringstream ss(l);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (!l.empty() && l.back() == ',') f.emplace_back();
    return f;
  };
  const std::size_t columns = split(line).size();
  int rows = 0, relocs_after_base = 0, correct_after_base = 0, wrong_at_30s = 0;
  while (std::getline(csv, line)) {
    const std::vector<std::string> f = split(line);
    ASSERT_EQ(f.size(), columns) << line;
    ++rows;
    EXPECT_EQ(f[13], f[4]) << "the match of the cycle is joined: " << line;  // template = target here
    if (f[2] != "relocalise") {
      EXPECT_EQ(f[10], "") << line;
      EXPECT_EQ(f[12], "") << line;
      continue;
    }
    EXPECT_EQ(f[12], f[10] == "1" ? "correct" : "false") << line;  // the closure column
    if (f[11] == "1") {
      ++relocs_after_base;
      correct_after_base += f[10] == "1";
    }
    if (f[10] == "0") {
      ++wrong_at_30s;
      EXPECT_NEAR(std::stod(f[1]), 30.0, 1e-6);
      EXPECT_EQ(f[4], "3");
      EXPECT_GT(std::stod(f[8]), 1.0);  // 27 s = 1.35 revolutions from where experience 3 was made
    }
  }
  EXPECT_EQ(rows, 20 + 19 + 1 + 1);  // new in the first revolution, re-localisations, experience 20, same
  EXPECT_EQ(relocs_after_base, 19);  // ARCR 18/19 in the JSON
  EXPECT_EQ(correct_after_base, 18);
  EXPECT_EQ(wrong_at_30s, 1);
}

TEST_F(VitaEvalBinary, AttributesEachCycleToTheSimulatedFaultsActiveThen) {
  Script script;
  script.board_fault = true;
  write_log(file("vita.lcmlog"), script);
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + " --trace " + file("trace") + " --json " + file("m.json"),
                          file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));
  EXPECT_NE(read_text(file("stdout.txt")).find("simulated faults (SIM_FAULT): board_offline 2;"), std::string::npos)
      << read_text(file("stdout.txt"));
  const nlohmann::json j = nlohmann::json::parse(read_text(file("m.json")));
  ASSERT_EQ(j["runs"][0]["faults"].size(), 2u);
  EXPECT_EQ(j["runs"][0]["faults"][0]["fault"], "board_offline 2");
  EXPECT_EQ(j["runs"][0]["faults"][1]["active"], false);
  std::istringstream csv(read_text(file("trace/vita_trace.csv")));
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_NE(line.find(",active_faults"), std::string::npos);
  int with = 0, without = 0;
  while (std::getline(csv, line)) {
    const double t = std::stod(line.substr(line.find(',') + 1));
    const bool listed = line.find(",board_offline 2,") != std::string::npos;
    if (t >= 10.0 - 1e-6 && t < 25.0 - 1e-6) {
      EXPECT_TRUE(listed) << line;
      ++with;
    } else {
      EXPECT_FALSE(listed) << line;
      ++without;
    }
  }
  EXPECT_EQ(with, 14);  // cycles at 10..19 s and 21..24 s (the script has no event at 20 s)
  EXPECT_GT(without, 20);
}

TEST_F(VitaEvalBinary, ADamagedLogIsEvaluatedFromWhatCanBeReadAndTheDamageReported) {
  write_log(file("vita.lcmlog"), Script{});
  std::string bytes = read_text(file("vita.lcmlog"));
  // Ten bytes of garbage before an event in the middle (a disk error), and half an event at the end
  // (a logger that died mid-write): 40 bytes in 2 places.
  const size_t middle = bytes.size() / 2;
  const size_t sync = bytes.find("\xED\xA1\xDA\x01", middle);
  ASSERT_NE(sync, std::string::npos);
  bytes.insert(sync, "JUNK!JUNK!");
  const std::string half_event = bytes.substr(sync + 10, 30);
  bytes += half_event;
  std::ofstream(file("damaged.lcmlog"), std::ios::binary) << bytes;
  ASSERT_EQ(run_vita_eval("--input " + file("damaged.lcmlog") + " --json " + file("out.json"), file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));
  const std::string out = read_text(file("stdout.txt"));
  EXPECT_NE(out.find(file("damaged.lcmlog") + ": corrupt LCM log: no event sync word at byte " + std::to_string(sync)),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("40 bytes skipped in 2 places, the last event cut off"), std::string::npos) << out;
  const nlohmann::json j = nlohmann::json::parse(read_text(file("out.json")));
  EXPECT_NE(j["runs"][0]["log_damage"].get<std::string>().find("corrupt LCM log"), std::string::npos);
  EXPECT_EQ(j["runs"][0]["counts"]["map_experiences"], 21) << "the map after the damage was read";
  // An undamaged log says so with null.
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + " --json " + file("out2.json"), file("stdout2.txt")), 0);
  EXPECT_TRUE(nlohmann::json::parse(read_text(file("out2.json")))["runs"][0]["log_damage"].is_null());
}

TEST_F(VitaEvalBinary, MeasuresTheRecoveryFromAKidnapInTheTableTheJsonTheTraceAndAPlot) {
  Script script;
  script.kidnap = true;
  write_log(file("vita.lcmlog"), script);
  const std::string outputs = " --json " + file("m.json") + " --plots " + file("plots") + " --trace " + file("trace");
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + outputs, file("stdout.txt")), 0) << read_text(file("stdout.txt"));
  const nlohmann::json j = nlohmann::json::parse(read_text(file("m.json")));
  const nlohmann::json& loc = j["runs"][0]["localisation"];
  ASSERT_TRUE(loc.is_object()) << j["runs"][0].dump(2);
  EXPECT_NEAR(loc["lap_length_m"].get<double>(), kTwoPi, 1e-3);
  ASSERT_EQ(loc["instants"].size(), 1u);
  const nlohmann::json& k = loc["instants"][0];
  EXPECT_EQ(k["kind"], "kidnap");
  EXPECT_EQ(k["utime"], kStart + 25 * kSecond);
  EXPECT_NEAR(k["t_s"].get<double>(), 25.0, 1e-9);
  EXPECT_EQ(k["localised"], true) << "the correct one at 28 s did not hold: the false one at 30 s followed";
  EXPECT_EQ(k["localised_utime"], kStart + 31 * kSecond);
  EXPECT_EQ(k["localised_to_id"], 1);
  EXPECT_NEAR(k["time_to_localise_s"].get<double>(), 6.0, 1e-9);
  EXPECT_NEAR(k["distance_to_localise_m"].get<double>(), 6.0 * kTwoPi / kPeriodS, 1e-3);
  EXPECT_NEAR(k["laps_to_localise"].get<double>(), 0.3, 1e-3);
  EXPECT_EQ(k["false_localisations"], 1);
  EXPECT_NEAR(k["false_localisation_events"][0]["position_error_m"].get<double>(), 2.0 * std::sin(3.0 * kPi / 20.0), 1e-4);
  EXPECT_NEAR(k["localising_s"].get<double>(), 3.0, 1e-9);
  EXPECT_NEAR(k["lem_after_m"].get<double>(), 0.0, 1e-9);
  EXPECT_EQ(k["lem_after_events"], 9);
  EXPECT_EQ(loc["summary"]["within_one_lap"], 1);
  EXPECT_EQ(loc["summary"]["false_localisations"], 1);
  EXPECT_TRUE(j["runs"][0]["faults"].empty()) << "a kidnap is an instant, not a fault that is active";
  // ATE leaves out the poses reported while LOCALISING (25-28 s at 10 Hz), and counts them.
  EXPECT_EQ(j["runs"][0]["ate"]["samples_localising"], 30);
  EXPECT_EQ(j["runs"][0]["ate"]["samples_used"], 401 - 30);
  const std::string table = read_text(file("stdout.txt"));
  EXPECT_NE(table.find("kidnap at 25.000 s: localised after 6.00 s, 1.88 m (0.30 laps) onto experience 1"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("<=1 lap"), std::string::npos) << table;
  const std::string trace = read_text(file("trace/vita_trace.csv"));
  EXPECT_NE(trace.find(",active_faults,localisation,localisation_marks\n"), std::string::npos);
  EXPECT_NE(trace.find(",26.000,same,5,5,"), std::string::npos) << "staying on the experience of 25 s";
  const auto row = [&](const std::string& key) {
    const std::size_t at = trace.find(key);
    return at == std::string::npos ? std::string() : trace.substr(at, trace.find('\n', at) - at);
  };
  EXPECT_NE(row(",26.000,same,").find(",localising,kidnap"), std::string::npos) << row(",26.000,same,");
  EXPECT_NE(row(",30.000,relocalise,").find(",tracking,false_localisation"), std::string::npos) << row(",30.000,");
  EXPECT_NE(row(",31.000,relocalise,").find(",tracking,localised"), std::string::npos) << row(",31.000,");
  const cv::Mat png = cv::imread(file("plots/vita_localisation.png"));
  ASSERT_FALSE(png.empty());
  EXPECT_TRUE(std::filesystem::exists(file("plots/vita_localisation.svg")));
  EXPECT_GT(count_colour(png, 40, 160, 40), 50);    // the first correct localisation (green)
  EXPECT_GT(count_colour(png, 40, 40, 220), 20);    // the false one (red)
  EXPECT_GT(count_colour(png, 120, 220, 255), 100);  // the LOCALISING stretch (band)
}

// No output onto a file vita-eval reads: the --json (the input by its path, a hard link to the
// --map-truth log), a trace or a plot that is a link to the input: exit 2 with the line naming both,
// and the file untouched (the JSON used to replace the log). The JSON is refused before the logs are
// read, the traces and plots before the first of them is written.
TEST_F(VitaEvalBinary, AnOutputThatIsAFileItReadsIsRefusedAndTheFileIsUntouched) {
  namespace fs = std::filesystem;
  const std::string log = file("vita.lcmlog"), truth = file("truth.lcmlog");
  write_log(log, Script{});
  write_log(truth, Script{});
  const std::string before = read_text(log), truth_before = read_text(truth);
  fs::create_hard_link(truth, file("truth-link.json"));
  fs::create_directories(file("trace"));
  fs::create_symlink(log, file("trace/vita_trace.csv"));
  fs::create_directories(file("plots"));
  fs::create_hard_link(log, file("plots/vita_trail.png"));
  const std::string refused = "): writing it would destroy it\n";
  EXPECT_EQ(WEXITSTATUS(run_vita_eval("--input " + log + " --json " + log, file("out1.txt"))), 2);
  EXPECT_EQ(read_text(file("out1.txt")), "vita-eval: --json " + log + " is the file given to --input (" + log + refused);
  EXPECT_EQ(WEXITSTATUS(run_vita_eval("--input " + log + " --map-truth " + truth + " --json " + file("truth-link.json"),
                                      file("out2.txt"))),
            2);
  EXPECT_EQ(read_text(file("out2.txt")),
            "vita-eval: --json " + file("truth-link.json") + " is the file given to --map-truth (" + truth + refused);
  EXPECT_EQ(WEXITSTATUS(run_vita_eval("--input " + log + " --trace " + file("trace") + " --plots " + file("plots"),
                                      file("out3.txt"))),
            2);
  const std::string out3 = read_text(file("out3.txt"));
  EXPECT_NE(out3.find("vita-eval: --trace " + file("trace/vita_trace.csv") + " is the file given to --input (" + log +
                      refused),
            std::string::npos)
      << out3;
  EXPECT_FALSE(fs::exists(file("plots/vita_experience_map.png"))) << "the traces are checked before any plot is written";
  fs::remove(file("trace/vita_trace.csv"));
  EXPECT_EQ(WEXITSTATUS(run_vita_eval("--input " + log + " --plots " + file("plots"), file("out4.txt"))), 2);
  const std::string out4 = read_text(file("out4.txt"));
  EXPECT_NE(out4.find("vita-eval: --plots " + file("plots/vita_trail.png") + " is the file given to --input (" + log +
                      refused),
            std::string::npos)
      << out4;
  EXPECT_TRUE(read_text(log) == before) << "the input log was written";
  EXPECT_TRUE(read_text(truth) == truth_before) << "the --map-truth log was written";

  ASSERT_EQ(::mkfifo(file("fifo.json").c_str(), 0644), 0);
  EXPECT_EQ(WEXITSTATUS(run_vita_eval("--input " + log + " --json " + file("fifo.json"), file("out5.txt"))), 2);
  EXPECT_EQ(read_text(file("out5.txt")), "vita-eval: --json " + file("fifo.json") + ": is a FIFO, not a regular file\n");
}

TEST_F(VitaEvalBinary, ASecondSessionIsJudgedByTheFirstSessionsTruthAndAClockThatOverlapsItIsRefused) {
  write_log(file("session1.lcmlog"), Script{});
  Script second;
  second.second_session = true;
  write_log(file("session2.lcmlog"), second);
  ASSERT_EQ(run_vita_eval("--input " + file("session2.lcmlog") + " --map-truth " + file("session1.lcmlog") + " --json " +
                              file("m.json"),
                          file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));
  const nlohmann::json j = nlohmann::json::parse(read_text(file("m.json")));
  const nlohmann::json& k = j["runs"][0]["localisation"]["instants"].at(0);
  EXPECT_EQ(k["kind"], "session_start") << "detected: the map is older than the log";
  EXPECT_EQ(k["utime"], kStart + 1000 * kSecond);
  EXPECT_EQ(k["localised"], true);
  EXPECT_EQ(k["localised_utime"], kStart + 1031 * kSecond);
  EXPECT_EQ(k["false_localisations"], 1);
  EXPECT_NEAR(k["laps_to_localise"].get<double>(), 1.55, 1e-3);
  EXPECT_TRUE(j["runs"][0]["alignment"]["valid"]) << "the first experience, made in session 1, is on its truth";
  // Without the first session's truth: nothing to judge the map by, and a line says so.
  ASSERT_EQ(run_vita_eval("--input " + file("session2.lcmlog") + " --json " + file("blind.json"), file("blind.txt")), 0);
  EXPECT_NE(read_text(file("blind.txt")).find("(--map-truth)"), std::string::npos) << read_text(file("blind.txt"));
  const nlohmann::json blind = nlohmann::json::parse(read_text(file("blind.json")));
  EXPECT_EQ(blind["runs"][0]["localisation"]["instants"][0]["localised"], false);
  // The same clock in both sessions: refused with one line.
  EXPECT_EQ(WEXITSTATUS(run_vita_eval("--input " + file("session1.lcmlog") + " --map-truth " + file("session1.lcmlog"),
                                      file("overlap.txt"))),
            1);
  const std::string err = read_text(file("overlap.txt"));
  EXPECT_EQ(err.rfind("vita-eval: --map-truth ", 0), 0u) << err;
  EXPECT_NE(err.find("overlaps"), std::string::npos) << err;
  EXPECT_EQ(count(err, "\n"), 1) << err;
}

TEST_F(VitaEvalBinary, PrintsOneRowPerInputAndNullArcrWithoutReLocalisations) {
  write_log(file("vita.lcmlog"), Script{});
  write_log(file("tactile.lcmlog"), Script{vita_pose_t::MODE_TACTILE, false});
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + " --input " + file("tactile.lcmlog") + " --json " +
                              file("out.json"),
                          file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));
  const nlohmann::json j = nlohmann::json::parse(read_text(file("out.json")));
  ASSERT_EQ(j["runs"].size(), 2u);
  EXPECT_EQ(j["runs"][1]["label"], "tactile");
  EXPECT_TRUE(j["runs"][1]["exm"]["arcr"].is_null());
  EXPECT_NEAR(j["runs"][1]["exm"]["arr"].get<double>(), 0.0, 1e-12);
  const std::string table = read_text(file("stdout.txt"));
  EXPECT_NE(table.find("\ntactile "), std::string::npos);
  EXPECT_NE(table.find("n/a"), std::string::npos);
}

TEST_F(VitaEvalBinary, NoPoseWithinTheGroundTruthIsNoLemNotAPerfectOne) {
  Script late;
  late.pose_delay_us = 1000 * kSecond;
  write_log(file("late.lcmlog"), late);
  ASSERT_EQ(run_vita_eval("--input " + file("late.lcmlog") + " --json " + file("out.json"), file("stdout.txt")), 0)
      << read_text(file("stdout.txt"));
  const nlohmann::json run = nlohmann::json::parse(read_text(file("out.json")))["runs"][0];
  EXPECT_EQ(run["lem"]["samples_used"], 0);
  EXPECT_GT(run["lem"]["samples_outside_gt"].get<int>(), 0);
  EXPECT_TRUE(run["lem"]["position_m"].is_null()) << run["lem"];
  EXPECT_TRUE(run["lem"]["orientation_rad"].is_null()) << run["lem"];
  EXPECT_EQ(run["ate"]["samples_used"], 0);
  EXPECT_TRUE(run["ate"]["position_m"].is_null()) << run["ate"];
  EXPECT_FALSE(run["ate"]["alignment"]["valid"]);
}

// --tum: the trajectory ATE uses and the ground truth, in the TUM format other tools read (evo,
// the TUM benchmark's scripts): a line per pose, seconds with microseconds, a unit quaternion.
TEST_F(VitaEvalBinary, WritesTheTrajectoryAndTheGroundTruthInTheTumFormat) {
  Script script;
  script.kidnap = true;  // 30 poses reported while LOCALISING: not in the trajectory
  write_log(file("vita.lcmlog"), script);
  ASSERT_EQ(run_vita_eval("--input " + file("vita.lcmlog") + " --tum " + file("tum"), file("stdout.txt")), 0)
      << read_text(file("stdout.txt"));
  const auto lines = [](const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string l; std::getline(in, l);) out.push_back(l);
    return out;
  };
  const std::vector<std::string> est = lines(read_text(file("tum/vita_estimate.tum")));
  const std::vector<std::string> gt = lines(read_text(file("tum/vita_groundtruth.tum")));
  ASSERT_EQ(est.size(), 1u + 401u - 30u);
  ASSERT_EQ(gt.size(), 1u + 2001u);
  EXPECT_EQ(est[0], "# timestamp x y z qx qy qz qw");
  // The first pose: at kStart, exactly map_pose(kStart); the timestamp keeps the microseconds.
  std::istringstream first(est[1]);
  std::string stamp;
  double x = 0, y = 0, z = 1, qx = 1, qy = 1, qz = 0, qw = 0;
  first >> stamp >> x >> y >> z >> qx >> qy >> qz >> qw;
  EXPECT_EQ(stamp, "1700000000.000000");
  const Pose2 p = map_pose(kStart);
  EXPECT_NEAR(x, p.x, 1e-8);
  EXPECT_NEAR(y, p.y, 1e-8);
  EXPECT_EQ(z, 0.0);
  EXPECT_EQ(qx, 0.0);
  EXPECT_EQ(qy, 0.0);
  EXPECT_NEAR(2.0 * std::atan2(qz, qw), p.theta, 1e-8);
  EXPECT_NEAR(qz * qz + qw * qw, 1.0, 1e-8);
  std::istringstream second(gt[2]);  // 20 ms after the first ground-truth sample
  second >> stamp;
  EXPECT_EQ(stamp, "1700000000.020000");
  // 25.1 s, reported while LOCALISING, is not in the trajectory; 28.0 s is.
  EXPECT_EQ(read_text(file("tum/vita_estimate.tum")).find("1700000025.100000 "), std::string::npos);
  EXPECT_NE(read_text(file("tum/vita_estimate.tum")).find("1700000028.000000 "), std::string::npos);
}

TEST_F(VitaEvalBinary, FailsWithAOneLineReasonOnALogThatIsNoSlamdOutputOrABadOption) {
  {
    LogWriterBus bus(file("nomap.lcmlog"));
    pose2d_t gt{};
    publish(bus, "GROUND_TRUTH", gt);
  }
  EXPECT_NE(run_vita_eval("--input " + file("nomap.lcmlog"), file("stdout.txt")), 0);
  EXPECT_NE(read_text(file("stdout.txt")).find("no VITA_MAP"), std::string::npos);
  EXPECT_NE(run_vita_eval("--input " + file("missing.lcmlog"), file("stdout2.txt")), 0);
  write_log(file("vita.lcmlog"), Script{});
  EXPECT_NE(run_vita_eval("--input " + file("vita.lcmlog") + " --centre 1:2", file("stdout3.txt")), 0);
  EXPECT_NE(read_text(file("stdout3.txt")).find("--centre must be X,Y"), std::string::npos);
  EXPECT_NE(run_vita_eval("--input " + file("vita.lcmlog") + " --start 1,2", file("stdout4.txt")), 0);
  EXPECT_NE(read_text(file("stdout4.txt")).find("--start must be X,Y,THETA_DEG"), std::string::npos);
  EXPECT_NE(run_vita_eval("--input " + file("vita.lcmlog") + " --world " + file("missing.yaml"), file("stdout5.txt")), 0);
  EXPECT_NE(read_text(file("stdout5.txt")).find("--world " + file("missing.yaml")), std::string::npos);
}

TEST_F(VitaEvalBinary, ABadFalseClosureToleranceExitsTwoWithOneLine) {
  write_log(file("vita.lcmlog"), Script{});
  for (const auto& [value, says] : std::vector<std::pair<std::string, std::string>>{
           {"0.25", "vita-eval: --false-closure-tolerance must be M,DEG (metres, degrees), got '0.25'"},
           {"0.25,-1", "vita-eval: --false-closure-tolerance: M must be a positive distance and DEG in (0, 180]"},
           {"0.05,15", "vita-eval: --false-closure-tolerance 0.05,15 is narrower than the correct-relocalisation"}}) {
    const int status = run_vita_eval("--input " + file("vita.lcmlog") + " --false-closure-tolerance " + value,
                                     file("stdout.txt"));
    ASSERT_TRUE(WIFEXITED(status)) << value;
    EXPECT_EQ(WEXITSTATUS(status), 2) << value;
    const std::string out = read_text(file("stdout.txt"));
    EXPECT_EQ(out.rfind(says, 0), 0u) << value << ": " << out;
    EXPECT_EQ(count(out, "\n"), 1) << "one line: " << out;
  }
}

TEST_F(VitaEvalBinary, ARunWithoutGroundTruthIsDrawnAndItsTruthMetricsAreUnavailable) {
  Script script;
  script.ground_truth = false;
  write_log(file("real.lcmlog"), script);
  ASSERT_EQ(run_vita_eval("--input " + file("real.lcmlog") + " --json " + file("out.json") + " --plots " + file("plots") +
                              " --trace " + file("trace"),
                          file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));
  const nlohmann::json run = nlohmann::json::parse(read_text(file("out.json")))["runs"][0];
  EXPECT_EQ(run["ground_truth"], false);
  EXPECT_NE(run["unavailable"].get<std::string>().find("no ground truth"), std::string::npos);
  for (const char* metric : {"arcr", "arcr_after_base", "valid_fraction", "correct_total", "arr"}) {
    EXPECT_TRUE(run["exm"][metric].is_null()) << metric << ": " << run["exm"];
  }
  EXPECT_TRUE(run["enm"]["enm"].is_null());
  EXPECT_TRUE(run["lem"].is_null());
  EXPECT_EQ(run["exm"]["relocalisations_total"], 19) << "the events are counted, not judged";
  EXPECT_EQ(run["exm"]["experiences_created"], 21);
  const std::string table = read_text(file("stdout.txt"));
  EXPECT_NE(table.find("n/a — no ground truth"), std::string::npos) << table;
  for (const char* plot : {"experience_map", "trail", "relocalisations"}) {
    for (const char* ext : {".png", ".svg"}) {
      EXPECT_TRUE(std::filesystem::exists(file(std::string("plots/vita_") + plot + ext))) << plot << ext;
    }
  }
  const cv::Mat map_png = cv::imread(file("plots/vita_experience_map.png"));
  ASSERT_FALSE(map_png.empty());
  EXPECT_GT(count_colour(map_png, 0, 140, 255), 100);  // dense experiences (orange)
  EXPECT_EQ(count(read_text(file("plots/vita_trail.svg")), "class=\"relocalisation\""), 19);
  EXPECT_TRUE(std::filesystem::exists(file("trace/vita_trace.csv")));

  // ARR needs only the base set, which --base-duration gives without truth: the same 19/20 as with it.
  ASSERT_EQ(run_vita_eval("--input " + file("real.lcmlog") + " --base-duration 20 --json " + file("out2.json"),
                          file("stdout2.txt")),
            0);
  const nlohmann::json run2 = nlohmann::json::parse(read_text(file("out2.json")))["runs"][0];
  EXPECT_NEAR(run2["exm"]["arr"].get<double>(), 19.0 / 20.0, 1e-12);
  EXPECT_TRUE(run2["exm"]["arcr"].is_null());
}

TEST_F(VitaEvalBinary, APlotTooFarFromTheOriginForItsSizeIsRefusedWithOneLineAndOneAtAMillionMetresIsDrawn) {
  Script script;
  script.ground_truth = false;  // drawn from --start: the run placed where the option says
  write_log(file("real.lcmlog"), script);
  // A 2 m run 1e17 m out: the grid's step (0.5 m) is below the rounding of the values (16 m).
  const std::string bounded = "timeout 60 " + std::string(VITA_EVAL_BINARY);
  const std::string cmd = bounded + " --input " + file("real.lcmlog") + " --plots " + file("far") +
                          " --start 1e17,-1e17,0 > " + file("far.txt") + " 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1) << "124 is the timeout: the grid loop never ended\n" << read_text(file("far.txt"));
  const std::string out = read_text(file("far.txt"));
  EXPECT_EQ(count(out, "cannot plot"), 1) << out;
  EXPECT_NE(out.find("vita-eval: cannot plot 'vita: experience map"), std::string::npos) << out;
  EXPECT_NE(out.find("lie 1e+17 m from the origin"), std::string::npos) << out;

  ASSERT_EQ(run_vita_eval("--input " + file("real.lcmlog") + " --plots " + file("near") + " --start 1e6,-1e6,0",
                          file("near.txt")),
            0)
      << read_text(file("near.txt"));
  EXPECT_TRUE(std::filesystem::exists(file("near/vita_experience_map.svg")));
}

TEST_F(VitaEvalBinary, RunsOfTheSameModeGetTheirOwnPlotsAndOneFigureSideBySide) {
  write_log(file("a.lcmlog"), Script{});
  write_log(file("b.lcmlog"), Script{vita_pose_t::MODE_VITA, false});
  write_log(file("c.lcmlog"), Script{vita_pose_t::MODE_TACTILE, false});
  ASSERT_EQ(run_vita_eval("--input " + file("a.lcmlog") + " --input " + file("b.lcmlog") + " --input " +
                              file("c.lcmlog") + " --plots " + file("plots"),
                          file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));
  const std::string a = read_text(file("plots/vita_experience_map.svg"));
  const std::string b = read_text(file("plots/vita-2_experience_map.svg"));
  EXPECT_EQ(count(a, "class=\"experience"), 21);
  EXPECT_EQ(count(b, "class=\"experience"), 39) << "the second vita run's own map (no loop closure)";
  EXPECT_TRUE(std::filesystem::exists(file("plots/vita-2_experience_map.png")));
  EXPECT_TRUE(std::filesystem::exists(file("plots/tactile_trail.png")));
  const std::string side = read_text(file("plots/comparison.svg"));
  EXPECT_EQ(count(side, "<g class=\"panel\">"), 3) << "a panel per run";
  EXPECT_EQ(count(side, "class=\"experience"), 21 + 39 + 39);
  const cv::Mat png = cv::imread(file("plots/comparison.png"));
  ASSERT_FALSE(png.empty());
  EXPECT_GT(png.cols, 3 * png.rows / 2) << "side by side";
}

// A short simulated run through slamd, its GROUND_TRUTH filtered out: a real robot's log.
class VitaEvalOnARealRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = whiskeye::testing::scratch_dir("vita_eval_real_run");
    const std::string src = WHISKEYE_SOURCE_DIR;
    const std::string sim = (dir_ / "sim.lcmlog").string();
    const std::string slam = (dir_ / "slam.lcmlog").string();
    whiskeye::testing::Subprocess s({VITA_SIM_EXE, "--world", src + "/config/worlds/aliased_arena.yaml", "--robot",
                                     src + "/config/robot.yaml", "--duration", "15", "--seed", "3", "--quiet",
                                     "--output", sim});
    ASSERT_EQ(s.wait(120), 0) << s.output();
    whiskeye::testing::Subprocess r({SLAMD_EXE, "--replay", sim, "--output", slam, "--mode", "vita", "--config",
                                     src + "/config/slam.yaml", "--robot", src + "/config/robot.yaml"});
    ASSERT_EQ(r.wait(120), 0) << r.output();
    std::filesystem::remove(sim);
    LogReader reader(slam);
    LogWriterBus writer((dir_ / "real.lcmlog").string());
    LogEvent ev;
    while (reader.next(ev)) {
      if (ev.channel == "GROUND_TRUTH") continue;
      writer.set_time(ev.utime);
      writer.publish_raw(ev.channel, ev.data);
    }
  }
  static std::string file(const std::string& name) { return (dir_ / name).string(); }
  static std::filesystem::path dir_;
};
std::filesystem::path VitaEvalOnARealRun::dir_;

TEST_F(VitaEvalOnARealRun, ExitsZeroWithTheTruthMetricsNullAndDrawsTheRunOverTheWorld) {
  const std::string world = std::string(WHISKEYE_SOURCE_DIR) + "/config/worlds/aliased_arena.yaml";
  ASSERT_EQ(run_vita_eval("--input " + file("real.lcmlog") + " --json " + file("out.json") + " --plots " +
                              file("plots") + " --world " + world,
                          file("stdout.txt")),
            0)
      << read_text(file("stdout.txt"));
  const nlohmann::json run = nlohmann::json::parse(read_text(file("out.json")))["runs"][0];
  EXPECT_EQ(run["ground_truth"], false);
  EXPECT_EQ(run["counts"]["ground_truth_samples"], 0);
  EXPECT_GT(run["counts"]["map_experiences"].get<int>(), 5);
  EXPECT_TRUE(run["exm"]["arcr"].is_null());
  EXPECT_TRUE(run["enm"]["enm"].is_null());
  EXPECT_TRUE(run["lem"].is_null());
  EXPECT_NE(read_text(file("stdout.txt")).find("n/a — no ground truth"), std::string::npos);

  // The arena (config/worlds/aliased_arena.yaml): 4 walls, 4 wall landmarks, 3 tactile landmarks,
  // under the map in every plot.
  const std::string svg = read_text(file("plots/vita_experience_map.svg"));
  EXPECT_EQ(count(svg, "class=\"wall\""), 4);
  EXPECT_EQ(count(svg, "class=\"visual-landmark\""), 4);
  EXPECT_EQ(count(svg, "class=\"tactile-landmark\""), 3);
  EXPECT_NE(svg.find("data-name=\"A_north (stripes)\""), std::string::npos);
  EXPECT_NE(svg.find("data-name=\"post_south\""), std::string::npos);
  EXPECT_LT(svg.find("class=\"wall\""), svg.find("class=\"experience")) << "the world is drawn under the map";
  EXPECT_NE(svg.find("world frame"), std::string::npos);
  EXPECT_GT(count(read_text(file("plots/vita_trail.svg")), "class=\"trail\""), 50);
  const cv::Mat png = cv::imread(file("plots/vita_experience_map.png"));
  ASSERT_FALSE(png.empty());
  EXPECT_GT(count_colour(png, 105, 105, 105), 1000);  // the walls (grey)
}

}  // namespace
}  // namespace whiskeye
