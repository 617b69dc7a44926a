// whiskerd.yaml and its calibration drop-ins (see config.h).
#include "whiskeye/whiskerd/config.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <system_error>
#include <utility>

namespace whiskeye::whiskerd {

namespace {

void load_calibration(const ParamNode& n, wp::WhiskerCalibration& c) {
  n.get("offset_x", c.offset_x, -4096.0, 4096.0);
  n.get("offset_y", c.offset_y, -4096.0, 4096.0);
  n.get("gain_x", c.gain_x, -1.0, 1.0);
  n.get("gain_y", c.gain_y, -1.0, 1.0);
  n.get("rotation", c.rotation, -7.0, 7.0);
  n.get("theta_offset", c.theta_offset, -1024.0, 1024.0);
  n.get("theta_gain", c.theta_gain, -0.01, 0.01);
  if (c.theta_gain == 0.0) throw ParamError(n.path_of("theta_gain") + " must not be 0");
}


// `calibration`: its `default` keys apply to every whisker, then `whiskers` entries to theirs. Keys
// absent keep what `p` holds, so the same loader reads whiskerd.yaml and every drop-in over it.
void load_calibration_section(const ParamNode& cal, CoreParams& p) {
  const ParamNode def = cal.section("default");
  for (wp::WhiskerCalibration& c : p.calibration) load_calibration(def, c);
  for (const ParamNode& w : cal.list("whiskers")) {
    int index = -1;
    w.require("index", index);
    if (index < 0 || index >= kN) w.fail("index", "= " + std::to_string(index) + " must be 0..23");
    load_calibration(w, p.calibration[index]);
    w.get("channel", p.channel[index], 0, kN - 1);
  }
}

// Every channel wired to exactly one whisker, naming the first channel taken twice.
void check_wiring(const CoreParams& p, const std::string& source) {
  std::array<int, kN> whisker_on{};
  whisker_on.fill(-1);
  for (int w = 0; w < kN; ++w) {
    const int ch = p.channel[w];
    if (whisker_on[ch] >= 0) {
      throw ParamError(source + ": 'calibration.whiskers' wires channel " + std::to_string(ch) + " to whiskers " +
                       std::to_string(whisker_on[ch]) + " and " + std::to_string(w) +
                       " (each channel belongs to one whisker: swap both entries)");
    }
    whisker_on[ch] = w;
  }
}

// whiskerd.yaml's sections a drop-in may not hold.
constexpr const char* kNotInDropin[] = {"can", "safety", "gpio", "realtime", "lcm", "rcp"};

}  // namespace

void load(const ParamNode& root, Params& p) {
  const ParamNode can = root.section("can");
  can.get("interface", p.interface);
  std::string mode = p.mode == wp::BusMode::kFd ? "fd" : "classic";
  can.get("mode", mode);
  if (mode == "fd") {
    p.mode = wp::BusMode::kFd;
  } else if (mode == "classic") {
    p.mode = wp::BusMode::kClassic;
  } else {
    throw ParamError(can.path_of("mode") + " = \"" + mode + "\" is not fd or classic");
  }
  if (p.mode == wp::BusMode::kClassic && !can.has("rate_hz")) p.rate_hz = 100.0;
  can.get("rate_hz", p.rate_hz, 10.0, 1000.0);
  if (p.mode == wp::BusMode::kClassic && p.rate_hz > 200.0) {
    throw ParamError(can.path_of("rate_hz") + " = " + std::to_string(p.rate_hz) +
                     " exceeds the classic-CAN bus capacity (max 200 Hz, see docs/can-protocol.md)");
  }
  can.get("stale_timeout_s", p.stale_timeout_s, 0.005, 10.0);
  if (p.stale_timeout_s < 2.0 / p.rate_hz) {
    throw ParamError(can.path_of("stale_timeout_s") + " = " + std::to_string(p.stale_timeout_s) +
                     " is less than two sample periods at rate_hz " + std::to_string(p.rate_hz) +
                     ": every board would be stale between its samples and the whiskers never run");
  }
  const ParamNode ids = can.section("ids");
  int sample = static_cast<int>(p.ids.sample_base), command = static_cast<int>(p.ids.command_base),
      heartbeat = static_cast<int>(p.ids.heartbeat_base);
  ids.get("sample_base", sample, 0, 0x7ff - wp::kNumBoards);
  ids.get("command_base", command, 0, 0x7ff - wp::kNumBoards);
  ids.get("heartbeat_base", heartbeat, 0, 0x7ff - wp::kNumBoards);
  // whiskerd receives samples and heartbeats through kernel filters on the aligned 8-id block
  // (mask 0x7f8, see main.cpp, `run`): node ids 1..6 must fall in base's own block.
  static_assert(wp::kNumBoards < 8, "node ids 1..kNumBoards fit one block of 8 ids");
  for (const auto& [key, base] : {std::pair<const char*, int>{"sample_base", sample}, {"heartbeat_base", heartbeat}}) {
    if (base % 8 != 0) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%03x", base);
      throw ParamError(ids.source() + ": '" + ids.path_of(key) + "' = " + hex +
                       " must be a multiple of 8 (0x...0 or 0x...8): the CAN filter covers the aligned block "
                       "base..base+7");
    }
  }
  auto overlap = [](int a, int b) { return std::abs(a - b) <= wp::kNumBoards; };
  if (overlap(sample, command) || overlap(sample, heartbeat) || overlap(command, heartbeat)) {
    throw ParamError(ids.path_of("sample_base") + ", command_base, heartbeat_base: id ranges overlap");
  }
  p.ids = {static_cast<uint32_t>(sample), static_cast<uint32_t>(command), static_cast<uint32_t>(heartbeat)};

  const ParamNode safety = root.section("safety");
  safety.get("retract_time_s", p.retract_time_s, 0.0, 10.0);
  safety.get("whisk_on_start", p.whisk_on_start);

  load_calibration_section(root.section("calibration"), p);

  const ParamNode gpio = root.section("gpio");
  gpio.get("enabled", p.gpio);
  gpio.get("enable_line", p.lines.enable);
  gpio.get("fault_line", p.lines.fault);
  gpio.get("estop_line", p.lines.estop);
  gpio.get("fault_active_low", p.lines.fault_active_low);
  gpio.get("estop_active_low", p.lines.estop_active_low);

  const ParamNode rt = root.section("realtime");
  rt.get("priority", p.rt_priority, 1, 99);
  rt.get("cpu", p.rt_cpu, -1, 1023);
  rt.get("lock_memory", p.lock_memory);

  const ParamNode lcm = root.section("lcm");
  lcm.get("url", p.lcm_url);
  lcm.get("channel_sample", p.channel_sample);
  lcm.get("channel_state", p.channel_state);
  lcm.get("channel_cycle", p.channel_cycle);
  lcm.get("channel_status", p.channel_status);
  lcm.get("status_period_s", p.status_period_s, 0.1, 60.0);

  rcp::load(root.section("rcp"), p.controller);
  root.check_no_unknown_keys();
  check_wiring(p, root.source());
}

void load_dropin(const ParamNode& dropin, CoreParams& p) {
  for (const char* key : kNotInDropin) {
    if (dropin.has(key)) dropin.fail(key, "is not allowed in a drop-in: a drop-in holds calibration keys only");
  }
  load_calibration_section(dropin.section("calibration"), p);
  dropin.check_no_unknown_keys();
  check_wiring(p, dropin.source());
}

std::filesystem::path dropin_dir(const std::filesystem::path& config) {
  std::filesystem::path dir = config;
  dir.replace_extension(".d");
  return dir;
}

std::vector<std::filesystem::path> dropin_files(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    if (!entry.is_regular_file()) throw ParamError(entry.path().string() + ": a drop-in must be a regular file");
    files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::pair<std::string, double>> calibration_keys(const CoreParams& p, int w) {
  const wp::WhiskerCalibration& c = p.calibration[static_cast<std::size_t>(w)];
  return {{"channel", p.channel[static_cast<std::size_t>(w)]},
          {"offset_x", c.offset_x},
          {"offset_y", c.offset_y},
          {"gain_x", c.gain_x},
          {"gain_y", c.gain_y},
          {"rotation", c.rotation},
          {"theta_offset", c.theta_offset},
          {"theta_gain", c.theta_gain}};
}

std::string format_dropin(const std::vector<CalibrationEntry>& entries, const std::string& comment) {
  std::string text;
  std::size_t start = 0;
  while (start < comment.size()) {
    const std::size_t end = std::min(comment.find('\n', start), comment.size());
    text += "# " + comment.substr(start, end - start) + "\n";
    start = end + 1;
  }
  text += "calibration:\n  whiskers:\n";
  for (const CalibrationEntry& e : entries) {
    text += "    - {index: " + std::to_string(e.index);
    for (const auto& [key, value] : e.keys) {
      char number[32];
      const auto written = std::to_chars(number, number + sizeof number, value);  // shortest that reads back the same
      text += ", " + key + ": " + std::string(number, written.ptr);
    }
    text += "}\n";
  }
  return text;
}

std::string load_with_dropins(const ParamNode& root, const std::string& config_path, Params& p) {
  load(root, p);
  std::string printed = root.dump();
  if (config_path.empty()) return printed;
  for (const std::filesystem::path& file : dropin_files(dropin_dir(config_path))) {
    const ParamNode dropin = ParamNode::from_file(file.string());
    load_dropin(dropin, p);
    printed += "# drop-in " + file.string() + "\n" + dropin.dump();
  }
  return printed;
}

}  // namespace whiskeye::whiskerd
