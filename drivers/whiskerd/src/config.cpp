// whiskerd.yaml and its calibration drop-ins (see config.h).
#include "whiskeye/whiskerd/config.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <utility>

namespace whiskeye::whiskerd {

namespace {

std::string shortest(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// `key` of `n` into `value`, refused (naming the file and the key) outside kCalibrationBounds.
void get_plausible(const ParamNode& n, const char* key, double& value) {
  n.get(key, value);
  if (!n.has(key)) return;
  if (const std::string why = implausible_calibration(key, value); !why.empty()) n.fail(key, "= " + shortest(value) + " " + why);
}

void load_calibration(const ParamNode& n, wp::WhiskerCalibration& c) {
  get_plausible(n, "offset_x", c.offset_x);
  get_plausible(n, "offset_y", c.offset_y);
  get_plausible(n, "gain_x", c.gain_x);
  get_plausible(n, "gain_y", c.gain_y);
  get_plausible(n, "rotation", c.rotation);
  get_plausible(n, "theta_offset", c.theta_offset);
  get_plausible(n, "theta_gain", c.theta_gain);
}

// A whisker's `index` (or its `channel`): 0..23 written in decimal. YAML reads 0x10 as 16 (and
// yaml-cpp 010 as 8): a number spelt so is no whisker anyone counts to.
int whisker_number(const ParamNode& n, const char* key, int value) {
  n.get(key, value);
  if (!n.has(key)) return value;
  const std::string text = n.text(key);
  const bool decimal = !text.empty() && text.size() <= 2 && (text.size() == 1 || text[0] != '0') &&
                       std::all_of(text.begin(), text.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
  if (!decimal || value < 0 || value >= kN) {
    n.fail(key, "= " + (text.empty() ? std::to_string(value) : text) + " must be 0..23, written in decimal");
  }
  return value;
}

// `calibration`: its `default` keys apply to every whisker, then `whiskers` entries to theirs. Keys
// absent keep what `p` holds, so the same loader reads whiskerd.yaml and every drop-in over it.
void load_calibration_section(const ParamNode& cal, CoreParams& p) {
  const ParamNode def = cal.section("default");
  for (wp::WhiskerCalibration& c : p.calibration) load_calibration(def, c);
  std::array<int, kN> entry_of{};  // the entry that gave each whisker, -1: none
  entry_of.fill(-1);
  int entry = 0;
  for (const ParamNode& w : cal.list("whiskers")) {
    if (!w.has("index")) w.fail("index", "is required but missing");
    const int index = whisker_number(w, "index", -1);
    if (entry_of[index] >= 0) {
      w.fail("index", "= " + std::to_string(index) + ": whisker " + std::to_string(index) + " has an entry already (" +
                          cal.path_of("whiskers") + "[" + std::to_string(entry_of[index]) +
                          "]): one entry per whisker in a file (merge them)");
    }
    entry_of[index] = entry++;
    load_calibration(w, p.calibration[index]);
    p.channel[index] = whisker_number(w, "channel", p.channel[index]);
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

bool is_dropin_name(const std::filesystem::path& file) { return file.extension() == ".yaml"; }

std::vector<std::filesystem::path> dropin_files(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  // Absent: no drop-ins. Anything else that is not a directory whiskerd can list (a symbolic link
  // loop, a link to nothing, a file, a directory it may not read) is a ParamError naming it (exit 2,
  // no restart): the calibration it was meant to hold would otherwise be lost without a word, or end
  // in an exit 1 that systemd restarts for ever.
  const auto refuse = [&](const fs::path& path, const std::string& what) {
    return ParamError(path.string() + ": " + what);
  };
  std::error_code ec;
  const fs::file_status link = fs::symlink_status(dir, ec);
  if (link.type() == fs::file_type::not_found) return files;
  if (ec) throw refuse(dir, "the drop-in directory cannot be read: " + ec.message());
  const fs::file_status target = fs::status(dir, ec);
  if (target.type() == fs::file_type::not_found) {
    throw refuse(dir, "the drop-in directory is a symbolic link to " + fs::read_symlink(dir, ec).string() +
                          ", which does not exist");
  }
  if (ec) throw refuse(dir, "the drop-in directory cannot be read: " + ec.message());
  if (target.type() != fs::file_type::directory) {
    throw refuse(dir, "the drop-in directory is not a directory (whiskerd reads its *.yaml files; remove it if none)");
  }
  fs::directory_iterator it(dir, ec);
  if (ec) throw refuse(dir, "the drop-in directory cannot be read: " + ec.message());
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) break;
    const fs::directory_entry& entry = *it;
    if (!is_dropin_name(entry.path())) continue;
    const fs::file_status st = entry.status(ec);  // a link followed
    if (ec) throw refuse(entry.path(), "a drop-in that cannot be read: " + ec.message());
    if (st.type() != fs::file_type::regular) throw refuse(entry.path(), "a drop-in must be a regular file");
    files.push_back(entry.path());
  }
  if (ec) throw refuse(dir, "the drop-in directory cannot be read: " + ec.message());
  std::sort(files.begin(), files.end());
  return files;
}

std::string implausible_calibration(const std::string& key, double v) {
  const CalibrationBounds& b = kCalibrationBounds;
  const auto outside = [](const std::string& range) { return "is outside the plausible " + range; };
  if (key == "offset_x" || key == "offset_y") {
    if (!(std::abs(v) <= b.max_offset_counts)) return outside("±" + shortest(b.max_offset_counts) + " counts");
  } else if (key == "gain_x" || key == "gain_y") {
    const double ratio = std::abs(v) / wp::WhiskerCalibration{}.gain_x;
    if (!(ratio >= b.min_gain_ratio && ratio <= b.max_gain_ratio)) {
      return outside(shortest(b.min_gain_ratio) + ".." + shortest(b.max_gain_ratio) + " x nominal (1/2047) in magnitude");
    }
  } else if (key == "rotation") {
    if (!(std::abs(v) <= b.max_rotation)) return outside("±" + shortest(b.max_rotation) + " rad (±90 deg)");
  } else if (key == "theta_offset") {
    if (!(std::abs(v) <= b.max_theta_offset_counts)) return outside("±" + shortest(b.max_theta_offset_counts) + " counts");
  } else if (key == "theta_gain") {
    const double ratio = std::abs(v) / wp::kThetaRadPerCount;
    if (!(ratio >= b.min_theta_gain_ratio && ratio <= b.max_theta_gain_ratio)) {
      return outside(shortest(b.min_theta_gain_ratio) + ".." + shortest(b.max_theta_gain_ratio) +
                     " x nominal (2 pi / 4096) in magnitude");
    }
  }
  return "";
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
