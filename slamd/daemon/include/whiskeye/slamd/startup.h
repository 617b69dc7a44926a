// slamd's startup policy, one unit for live and --replay: which state directory, whether to hold a
// checkpoint store at all, where the map comes from (--map, a resumed checkpoint, --fresh or a new
// map), and when a checkpoint is taken. How a checkpoint is written (at once in a replay, by the
// writer thread live) stays with the caller.
#pragma once

#include "whiskeye/slamd/checkpoint_store.h"
#include "whiskeye/slamd/slam_node.h"

#include "whiskeye/common/log.h"
#include "whiskeye/common/robot_geometry.h"
#include "whiskeye/slam/vita_slam.h"

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace whiskeye::slamd {

struct StartupOptions {
  std::string map_file;   // --map: start from this saved map
  bool localise = false;  // --localise: with --map, localise without growing it (no checkpoints)
  bool fresh = false;     // --fresh: ignore the checkpoints held (rotated out as new ones are written)
};

// Live slamd's state directory: `given` (--state-dir), else $STATE_DIRECTORY (systemd's
// StateDirectory=), else /var/lib/slamd.
std::string live_state_directory(const std::string& given);

// Opens the checkpoint store in `directory` into `store`, unless `directory` is empty (a replay
// without --state-dir) or `localise`: --localise writes no checkpoints, so it needs no state
// directory (nor its lock) and can run next to the service. Throws CheckpointError.
void open_store(std::optional<CheckpointStore>& store, const std::string& directory, int keep, bool localise);

// Where start_slam says what it chose (info) and what it skipped or cleaned up (warning).
using StartupLog = std::function<void(LogLevel, const std::string&)>;

// The SLAM state to start from, logging what was chosen:
//   --map FILE: that map (refused, if it would grow into a state directory holding another map's
//     checkpoints, unless --fresh or --localise);
//   else, unless --fresh, the newest usable checkpoint in `store` (corrupt ones skipped and logged;
//     an intact one that cannot be loaded here refuses the start);
//   else a new map.
// Throws std::runtime_error (or CheckpointError) with the reason and what the operator can do.
std::unique_ptr<slam::VitaSlam> start_slam(const slam::SlamParams& params, const RobotGeometry& robot,
                                           const StartupOptions& options, CheckpointStore* store,
                                           const StartupLog& log);

// Calls `checkpoint` after every `every`-th cycle the node processes; nothing when every <= 0.
void checkpoint_every(SlamNode& node, int every, std::function<void()> checkpoint);

}  // namespace whiskeye::slamd
