// whiskerd's configuration: whiskerd.yaml (Params: the core's CoreParams plus the CAN interface, the
// motor lines, real-time scheduling and LCM) and the calibration drop-ins of its directory
// (docs/deployment.md, "Calibration drop-ins"): whiskerd.yaml's drop-ins are whiskerd.d/*.yaml beside
// it, read in file-name order after it, each a whiskerd.yaml holding only `calibration` keys; a key a
// drop-in gives replaces the value the files before it gave. whiskeye-calibrate writes them, so the
// operator's file is never rewritten.
#pragma once

#include <whiskeye/common/channels.h>
#include <whiskeye/common/params.h>

#include <filesystem>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "whiskeye/gpio/motor_lines.h"
#include "whiskeye/whiskerd/whiskerd_core.h"

namespace whiskeye::whiskerd {

// The whole of whiskerd.yaml: the core's part and the daemon's.
struct Params : CoreParams {
  // can
  std::string interface = "can0";
  // gpio
  bool gpio = true;
  gpio::LineNames lines;
  // real time
  int rt_priority = 80;  // SCHED_FIFO priority of the control thread
  int rt_cpu = -1;       // pin the control thread to this CPU; -1 = no pinning
  bool lock_memory = true;
  // lcm
  std::string lcm_url;
  std::string channel_sample = channels::kWhiskerSample;
  std::string channel_state = channels::kRcpState;
  std::string channel_cycle = channels::kWhiskCycle;
  std::string channel_status = channels::kDriverStatus;
  double status_period_s = 1.0;
};

// Loads a whole whiskerd.yaml (every section optional); unknown keys and bad values throw ParamError
// naming the key.
void load(const ParamNode& root, Params& p);

// Applies one drop-in over `p`: its `calibration.default` keys to every whisker, then its
// `calibration.whiskers` entries to theirs (keys absent keep their value). Any key outside
// `calibration` is a ParamError naming the file and the key; so is a typo, a value outside
// kCalibrationBounds, an index that is not a decimal 0..23, and a whisker given two entries in one
// file (which one was meant cannot be known). whiskerd.yaml's `calibration` is read the same way.
void load_dropin(const ParamNode& dropin, CoreParams& p);

// The drop-in directory of a config file: /etc/whiskeye/whiskerd.yaml -> /etc/whiskeye/whiskerd.d.
std::filesystem::path dropin_dir(const std::filesystem::path& config);
// Whether whiskerd reads a file of this name in its drop-in directory: NAME.yaml (not NAME.yml, not
// a directory's name).
bool is_dropin_name(const std::filesystem::path& file);
// Its *.yaml files in file-name order (the order they apply in, later files win); none if the
// directory does not exist. A ParamError naming the path: the directory there but not one whiskerd
// can list (a symbolic link loop or to nothing, a file, unreadable), or a *.yaml in it that is not a
// regular file or cannot be looked at (a link loop).
std::vector<std::filesystem::path> dropin_files(const std::filesystem::path& dir);

// The calibration a WhiskEye's whisker can have: whiskerd's loader refuses a value outside these (in
// whiskerd.yaml or a drop-in) and whiskeye-calibrate never writes one, so a dead sensor (gain 0), a
// typo or a unit slip (a rotation in degrees) stops at the file, not in the map. Gains are bounded in
// magnitude: a mirrored board's are negative.
struct CalibrationBounds {
  double max_offset_counts = 512;                                  // |offset_x|, |offset_y|: a quarter of the ADC range
  double min_gain_ratio = 0.5, max_gain_ratio = 2.0;               // |gain_x|, |gain_y| / nominal (1/2047)
  double max_rotation = std::numbers::pi / 2;                      // rad: map and gain find it in (-pi/2, pi/2]
  double max_theta_offset_counts = 256;                            // 22.5 deg
  double min_theta_gain_ratio = 0.8, max_theta_gain_ratio = 1.25;  // |theta_gain| / nominal (2 pi / 4096)
};
inline constexpr CalibrationBounds kCalibrationBounds{};
// Why calibration key `key` (offset_x ... theta_gain) = `value` is implausible: "is outside the
// plausible ±512 counts", or "" when it is within kCalibrationBounds (any other key: "").
std::string implausible_calibration(const std::string& key, double value);

// Whisker w's calibration as whiskerd.yaml names it: channel, offset_x, offset_y, gain_x, gain_y,
// rotation, theta_offset, theta_gain.
std::vector<std::pair<std::string, double>> calibration_keys(const CoreParams& p, int w);

// One whisker's entry of a drop-in: its index and the calibration keys to give it, in order.
struct CalibrationEntry {
  int index = 0;
  std::vector<std::pair<std::string, double>> keys;  // e.g. {"offset_x", 12.5}, {"channel", 6}
};
// A drop-in's text: `comment` (each line prefixed "# "), then `calibration.whiskers` with the
// entries, numbers written so that load_dropin() reads back the same doubles.
std::string format_dropin(const std::vector<CalibrationEntry>& entries, const std::string& comment);

// whiskerd's whole configuration: `root` (the config file with the command line's overrides, or
// empty), then, when `config_path` is not empty, the drop-ins beside it. Returns what
// --print-config prints: the file's parameters, then each drop-in's under a "# drop-in <path>" line.
std::string load_with_dropins(const ParamNode& root, const std::string& config_path, Params& p);

}  // namespace whiskeye::whiskerd
