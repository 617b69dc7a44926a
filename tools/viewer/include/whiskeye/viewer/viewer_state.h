// What whiskeye-viewer shows, aggregated from the stack's messages: the experience map, the pose and
// its trail, the latest camera frame, this whisk cycle's contacts and deflections, the last
// VITA_EVENT / VITA_MATCH, and every daemon's DRIVER_STATUS / SLAM_STATUS. Pure: decoded (or
// encoded) messages in, JSON out; no clock, no socket, no file. The same state serves the live
// daemon (messages from LCM), an lcm-logplayer replay and a recorded log (LogTimeline), and tests.
//
// The JSON is split into sections, each with a version that changes when the section does, so the
// daemon sends a browser the whole state once (snapshot()) and then only what changed (delta()).
#pragma once

#include "whiskeye/viewer/camera_jpeg.h"

#include <nlohmann/json.hpp>
#include <whiskeye/driver_status_t.hpp>
#include <whiskeye/slam_status_t.hpp>
#include <whiskeye/template_match_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>
#include <whiskeye/whisk_cycle_t.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace whiskeye::viewer {

struct ViewerParams {
  std::size_t trail_max_points = 2000;  // oldest trail points dropped beyond this
  double trail_min_step_m = 0.02;       // a pose joins the trail once it is this far from the last point
  int64_t trail_period_us = 1'000'000;  // delta(): the trail at most this often (the pose every time)
  int64_t status_stale_us = 3'000'000;  // a daemon whose last status is older is shown stale (1 Hz reports)
  int camera_max_width = 320;           // camera frames are downscaled to at most this width
  int jpeg_quality = 75;
};

// The channels whose newest message replaces everything earlier ones said (a whole map, a frame, a
// whisk cycle): a log seek applies only the newest of them (LogTimeline).
bool is_latest_only(std::string_view channel);

// The daemon's state colour for a DRIVER_STATUS / SLAM_STATUS state code: "starting", "ok",
// "degraded", "fault", or "unknown" for a code outside the contract.
const char* state_name(int8_t state);

class ViewerState {
 public:
  enum Section { kMap, kPose, kTrail, kCamera, kWhiskers, kEvent, kMatch, kStatus, kMeta, kSections };
  using Versions = std::array<uint64_t, kSections>;
  // What one consumer of delta() has been sent.
  struct Cursor {
    Versions seen{};
    int64_t trail_sent_us = INT64_MIN;
  };

  explicit ViewerState(ViewerParams params = {});

  // Decodes one message of `channel` received at `recv_utime` (the wall clock live, the log's time in
  // a log) and applies it. A channel the viewer does not show is ignored (false). A message that does
  // not decode, or whose contents break the contract (a whisk cycle of the wrong size, a frame whose
  // pixels do not fit its header), is counted in the meta section's decode errors (false).
  // `owner`, when set, keeps `data` valid after the call (camera frames are then kept as views).
  bool apply(std::string_view channel, int64_t recv_utime, std::span<const uint8_t> data,
             std::shared_ptr<const void> owner = nullptr);
  // A message of a latest-only channel a log seek skipped (a newer one follows): counted, not shown.
  void skip(std::string_view channel, int64_t recv_utime);
  // The viewer's notion of now (the wall clock live, the slider's time in a log): statuses older than
  // status_stale_us turn stale. Receiving a message advances it too.
  void set_now(int64_t utime);

  // Typed entry points (what apply() calls after decoding).
  void on_map(const vita_map_t& m);
  void on_pose(const vita_pose_t& m);
  void on_event(const vita_event_t& m);
  void on_match(const template_match_t& m);
  void on_whisk_cycle(const whisk_cycle_t& m);
  void on_camera(Frame frame);
  void on_driver_status(const driver_status_t& m, int64_t recv_utime);
  void on_slam_status(const slam_status_t& m, int64_t recv_utime);

  // Every section, and "v": the state's version (it grows with every change; a page ignores an update
  // whose "v" is not above that of the snapshot it has).
  nlohmann::json snapshot() const;
  // The sections whose version differs from what `cursor` saw (it is updated to what was included);
  // an empty object when nothing changed, else with "v" as in snapshot(). The trail is included at most every trail_period_us of
  // `now_us` (it is the largest section and changes with every pose).
  nlohmann::json delta(Cursor& cursor, int64_t now_us) const;
  // One section, as snapshot() has it (/status takes two without building the map's).
  nlohmann::json section(Section s) const;
  const Versions& versions() const { return versions_; }
  uint64_t version() const { return version_counter_; }

  // The latest camera frame as a JPEG (downscaled to camera_max_width), encoded on the first call
  // after a frame arrived and cached; null when there is no frame or it cannot be converted.
  std::shared_ptr<const std::string> camera_jpeg() const;

  // For tests and the page's counters.
  int num_experiences() const { return map_.num_experiences; }
  int current_experience() const { return map_.current_experience_id; }
  std::size_t trail_size() const { return trail_.size(); }
  int64_t decode_errors() const { return decode_errors_; }
  int64_t messages(std::string_view channel) const;

 private:
  void bump(Section s) { versions_[s] = ++version_counter_; }
  void received(std::string_view channel, int64_t recv_utime);
  void decode_error(std::string_view channel, const std::string& reason);
  nlohmann::json map_json() const;
  nlohmann::json pose_json() const;
  nlohmann::json trail_json() const;
  nlohmann::json camera_json() const;
  nlohmann::json whiskers_json() const;
  nlohmann::json event_json() const;
  nlohmann::json match_json() const;
  nlohmann::json status_json() const;
  nlohmann::json meta_json() const;

  ViewerParams params_;
  Versions versions_{};
  uint64_t version_counter_ = 0;
  int64_t now_utime_ = 0;

  vita_map_t map_;
  int num_dense_ = 0;
  bool have_map_ = false;
  vita_pose_t pose_;
  bool have_pose_ = false;
  struct Point {
    double x, y;
  };
  std::deque<Point> trail_;
  vita_event_t event_;
  bool have_event_ = false;
  std::array<int64_t, 3> event_counts_{};  // by vita_event_t type: same, new, relocalise
  template_match_t match_;
  bool have_match_ = false;

  struct Whiskers {
    int64_t cycle = 0;
    int64_t utime = 0;
    int num_samples = 0;
    int num_missing = 0;
    std::vector<bool> contact, measured;
    std::vector<double> deflection;  // the cycle's peak |deflection| per whisker, 0..1
    std::vector<double> theta_max;   // the cycle's largest protraction per whisker, rad
  };
  Whiskers whiskers_;
  bool have_whiskers_ = false;

  Frame frame_;
  bool have_frame_ = false;
  mutable std::shared_ptr<const std::string> jpeg_;  // of frame_, once asked for
  mutable bool jpeg_tried_ = false;

  struct Daemon {
    std::string kind;  // "driver" or "slam"
    int8_t state = 0;
    std::string message;
    int64_t utime = 0;       // the report's own time
    int64_t recv_utime = 0;  // when it arrived (staleness)
    std::vector<std::pair<std::string, double>> counters, stats;
    bool stale = false;
  };
  std::map<std::string, Daemon> daemons_;
  template <typename Status>
  Daemon& status_record(const std::string& name, const char* kind, const Status& m, int64_t recv_utime);

  std::map<std::string, int64_t, std::less<>> messages_;
  int64_t decode_errors_ = 0;
  std::string last_decode_error_;
};

}  // namespace whiskeye::viewer
