// Converts VITA_POSE / VITA_EVENT / VITA_MAP / GROUND_TRUTH log events into EvalInput.
#include "log_input.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"
#include "whiskeye/common/wire_names.h"

#include <whiskeye/pose2d_t.hpp>
#include <whiskeye/sim_fault_t.hpp>
#include <whiskeye/template_match_t.hpp>
#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>

#include <cstdio>
#include <stdexcept>
#include <string>

namespace whiskeye::eval {

namespace {

// "board_offline 2", "odometry_slip x1.2", ...: what the trace lists while the fault is active.
std::string fault_name(const sim_fault_t& f) {
  switch (f.kind) {
    case sim_fault_t::KIND_DEAD_WHISKER: return "dead_whisker " + std::to_string(f.index);
    case sim_fault_t::KIND_BOARD_OFFLINE: return "board_offline " + std::to_string(f.index);
    case sim_fault_t::KIND_CAMERA_BLACKOUT: return "camera_blackout";
    case sim_fault_t::KIND_CAMERA_FREEZE: return "camera_freeze";
    case sim_fault_t::KIND_ODOMETRY_SLIP: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "odometry_slip x%g", f.value);
      return buf;
    }
    default: return "fault_kind_" + std::to_string(f.kind);
  }
}

template <typename T>
bool decode_counted(const LogEvent& ev, T& msg, LoadedRun& run) {
  if (decode_message(std::span<const uint8_t>(ev.data), msg)) return true;
  ++run.decode_errors[ev.channel];
  return false;
}

}  // namespace

LoadedRun load_run(const std::string& path) {
  LoadedRun run;
  run.path = path;
  LogReader reader(path, LogReader::Access::kStreamed);  // one pass; every event copied out
  LogEvent ev;
  vita_map_t last_map{};
  std::optional<int8_t> pose_mode;
  while (reader.next(ev)) {
    if (ev.channel == channels::kVitaPose) {
      vita_pose_t m{};
      if (!decode_counted(ev, m, run)) continue;
      run.input.estimate.push_back({m.utime, {m.x, m.y, m.theta}});
      run.input.states.push_back({m.utime, m.localisation == vita_pose_t::LOCALISATION_LOCALISING});
      pose_mode = m.mode;
    } else if (ev.channel == channels::kVitaEvent) {
      vita_event_t m{};
      if (!decode_counted(ev, m, run)) continue;
      EventType type = EventType::kSameExperience;
      if (m.type == vita_event_t::NEW_EXPERIENCE) {
        type = EventType::kNewExperience;
      } else if (m.type == vita_event_t::RELOCALISE) {
        type = EventType::kRelocalise;
      } else if (m.type != vita_event_t::SAME_EXPERIENCE) {
        ++run.decode_errors[ev.channel];  // an event type this contract does not know
        continue;
      }
      run.input.events.push_back(
          {m.utime, m.cycle, type, m.from_id, m.to_id, m.localisation == vita_pose_t::LOCALISATION_LOCALISING});
    } else if (ev.channel == channels::kVitaMap) {
      vita_map_t m{};
      if (!decode_counted(ev, m, run)) continue;
      last_map = std::move(m);
      ++run.map_messages;
    } else if (ev.channel == channels::kVitaMatch) {
      template_match_t m{};
      if (!decode_counted(ev, m, run)) continue;
      run.input.matches.push_back({m.utime, m.cycle, m.template_id, m.is_new != 0, m.error, m.visual_error,
                                   m.pfh_error, m.sda_error, m.visual_shift, m.visual_used != 0, m.tactile_used != 0});
    } else if (ev.channel == channels::kSimFault) {
      sim_fault_t m{};
      if (!decode_counted(ev, m, run)) continue;
      if (m.kind == sim_fault_t::KIND_KIDNAP) {
        run.input.kidnaps.push_back({m.utime, {m.x, m.y, m.theta}});  // an instant, not a fault that ends
      } else {
        run.input.faults.push_back({m.utime, fault_name(m), m.active != 0});
      }
    } else if (ev.channel == channels::kGroundTruth) {
      pose2d_t m{};
      if (!decode_counted(ev, m, run)) continue;
      run.input.ground_truth.push_back({m.utime, {m.x, m.y, m.theta}});
    }
  }
  run.log_damage = reader.damage().summary();
  if (run.map_messages == 0) {
    throw std::runtime_error(path + ": no VITA_MAP messages (is this a slamd output log?)");
  }
  for (const experience_t& e : last_map.experiences) {
    run.input.map.experiences.push_back({e.id, {e.x, e.y, e.theta}, e.utime_created, e.dense != 0});
  }
  for (const link_t& l : last_map.links) run.input.map.links.push_back({l.from_id, l.to_id, l.revoked != 0, {l.dx, l.dy, l.dtheta}});
  run.mode = mode_name(last_map.mode);
  if (run.mode == "unknown" && pose_mode) run.mode = mode_name(*pose_mode);
  return run;
}

std::vector<PoseSample> load_ground_truth(const std::string& path) {
  LogReader reader(path, LogReader::Access::kStreamed);
  LogEvent ev;
  std::vector<PoseSample> out;
  while (reader.next(ev)) {
    if (ev.channel != channels::kGroundTruth) continue;
    pose2d_t m{};
    if (decode_message(std::span<const uint8_t>(ev.data), m)) out.push_back({m.utime, {m.x, m.y, m.theta}});
  }
  if (out.empty()) throw std::runtime_error(path + ": no GROUND_TRUTH messages");
  return out;
}

}  // namespace whiskeye::eval
