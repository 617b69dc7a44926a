// Plain input/output structs of the ViTa-SLAM core (slamd/core). The daemon converts its messages
// into these; the core never sees LCM, files or clocks (time is always an argument, in µs).
#pragma once

#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/common/se2.h"

#include <array>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace whiskeye::slam {

// Which sensory terms exist at all (the three rows of the paper's Table I).
enum class Mode { Visual, Tactile, Vita };
// "visual" | "tactile" | "vita"; anything else throws std::invalid_argument naming the text.
Mode parse_mode(const std::string& text);
std::string to_string(Mode mode);
inline bool uses_visual(Mode m) { return m != Mode::Tactile; }
inline bool uses_tactile(Mode m) { return m != Mode::Visual; }

// Bad input that the core refuses (wrong sizes, unknown pixel format, corrupt JPEG...). The cycle
// goes on without that sense; the message names what was wrong.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// V4L2 FourCC codes of the pixel formats the visual template accepts.
constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(static_cast<uint8_t>(a)) | (static_cast<uint32_t>(static_cast<uint8_t>(b)) << 8) |
         (static_cast<uint32_t>(static_cast<uint8_t>(c)) << 16) | (static_cast<uint32_t>(static_cast<uint8_t>(d)) << 24);
}
constexpr uint32_t kPixGrey = fourcc('G', 'R', 'E', 'Y');
constexpr uint32_t kPixYuyv = fourcc('Y', 'U', 'Y', 'V');
constexpr uint32_t kPixRgb24 = fourcc('R', 'G', 'B', '3');
constexpr uint32_t kPixBgr24 = fourcc('B', 'G', 'R', '3');
constexpr uint32_t kPixMjpeg = fourcc('M', 'J', 'P', 'G');

// One camera frame, not owned. row_stride in bytes (ignored for MJPEG, whose data is the JPEG).
struct ImageView {
  int64_t utime = 0;
  int width = 0;
  int height = 0;
  int row_stride = 0;
  uint32_t pixelformat = kPixGrey;
  std::span<const uint8_t> data;
};

// One head sample of all 24 whiskers: protraction θ (rad), base deflection x/y (sensor units, the
// same units as RobotGeometry's bend_gain), and the head's own contact flag.
struct WhiskSample {
  int64_t utime = 0;
  bool valid = true;
  std::array<float, kNumWhiskers> theta{};
  std::array<float, kNumWhiskers> deflection_x{};
  std::array<float, kNumWhiskers> deflection_y{};
  std::array<bool, kNumWhiskers> contact{};
};

// All samples of one whisk cycle (one protraction + retraction), in time order.
struct WhiskCycleInput {
  int64_t cycle = 0;
  int64_t utime_start = 0;
  int64_t utime_end = 0;
  std::vector<WhiskSample> samples;
};

// Body-frame velocity (vx forward, vy left, omega ccw), valid over the interval that ends at utime
// (zero-order hold from the previous sample's utime).
struct OdometrySample {
  int64_t utime = 0;
  double vx = 0.0;
  double vy = 0.0;
  double omega = 0.0;
};

struct CycleInput {
  int64_t utime = 0;
  int64_t cycle = 0;
  const ImageView* image = nullptr;        // nullptr: no frame this cycle
  const WhiskCycleInput* whisk = nullptr;  // nullptr: no whisk data this cycle
  std::vector<OdometrySample> odometry;    // since the previous cycle, in time order
};

struct MatchResult {
  int template_id = -1;      // -1: no template this cycle (no usable sense)
  bool is_new = false;
  double error = 0.0;        // ε of the best stored template (0 for a new one when none existed)
  double visual_error = 0.0; // the three terms of ε, each already divided by its σ
  double pfh_error = 0.0;
  double sda_error = 0.0;
  int visual_shift = 0;      // columns; current column c matched stored column c − shift
  bool visual_used = false;
  bool tactile_used = false;
};

enum class EventType { SameExperience, NewExperience, Relocalise };

// How the cycle's view relates to one stored template (TemplateStore::Recogniser): recognised by the
// match's rules; seen only — vision alone would take it (V within threshold_visual) but touch objects
// (ViTa's veto); or neither. Touch differs between passes of one place (the whisk's phase, a contact
// or none), so its objection withholds support from a place but is no evidence against it.
enum class Recognition : uint8_t { None, SeenOnly, Recognised };
std::string to_string(EventType type);

struct Event {
  EventType type = EventType::SameExperience;
  int from_id = -1;
  int to_id = -1;
  // A template was recognised whose every experience lies beyond the odometry-consistency gate's
  // budget (one within it, even if the view-shift rule set it aside, is the same place seen from
  // another pose), and one of them would have been taken but for the gate: what the robot sees
  // disagrees with where it thinks it is.
  bool gate_refused = false;
};

struct CycleResult {
  MatchResult match;
  Event event;
  Pose2 pose;               // best estimate of the base in the map frame
  int experience_id = -1;   // current experience after this cycle
  double pc_x = 0.0;        // pose-cell best estimate, cells
  double pc_y = 0.0;
  double pc_theta = 0.0;
  int num_templates = 0;
  bool dense = false;       // this cycle's tactile template has contact data
  // ViTa without one of its senses this cycle: matched on the other, but no template, energy or
  // experience came of it (VitaSlam, step 2).
  bool degraded = false;
  // LOCALISING (a restart on a saved map, a suspected kidnap): `pose` is the dead-reckoned pose,
  // not to be trusted, and no template or experience was made; `hypotheses` places are weighed.
  bool localising = false;
  int hypotheses = 0;
  std::string image_warning;  // non-empty: the frame was refused (the cycle went on without vision), and why
  std::string whisk_warning;  // non-empty: the whisk cycle had no valid sample (went on without touch)
};

}  // namespace whiskeye::slam
