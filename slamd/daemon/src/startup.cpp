// slamd's startup policy: state directory, store, resume / --map / --fresh, checkpoint cadence.
#include "whiskeye/slamd/startup.h"

#include <cstdlib>
#include <stdexcept>
#include <utility>
#include <vector>

namespace whiskeye::slamd {

std::string live_state_directory(const std::string& given) {
  if (!given.empty()) return given;
  const char* sd = std::getenv("STATE_DIRECTORY");  // systemd StateDirectory=
  return sd ? sd : "/var/lib/slamd";
}

void open_store(std::optional<CheckpointStore>& store, const std::string& directory, int keep, bool localise) {
  if (!directory.empty() && !localise) store.emplace(directory, keep);
}

namespace {

std::unique_ptr<slam::VitaSlam> load_map(const slam::SlamParams& params, const RobotGeometry& robot,
                                         const StartupOptions& o, CheckpointStore* store,
                                         const StartupLog& log) {
  // Growing the loaded map writes its checkpoints into the state directory: whatever map is there
  // would be rotated out within --checkpoint-keep cycles. The operator says so with --fresh.
  if (!o.localise && !o.fresh && store != nullptr) {
    if (const auto held = store->list(); !held.empty()) {
      throw std::runtime_error("the state directory " + store->directory() + " holds " +
                               std::to_string(held.size()) + " checkpoint(s) of a map (newest " + held.back() +
                               ") that growing --map " + o.map_file +
                               " would rotate out: move them out of it first, or add --fresh to let them go "
                               "(or --localise, which writes no checkpoints)");
    }
  }
  const Checkpoint cp = read_checkpoint(o.map_file);
  std::unique_ptr<slam::VitaSlam> s;
  try {
    s = std::make_unique<slam::VitaSlam>(slam::VitaSlam::deserialise(cp.payload, params, robot));
  } catch (const std::exception& e) {
    throw std::runtime_error(o.map_file + ": " + e.what());
  }
  if (o.localise) s->set_localise_only(true);
  // The robot may be anywhere in the loaded map: every place is a candidate until one wins.
  s->start_localising(false);
  log(LogLevel::kInfo, "loaded map " + o.map_file + " (" + std::to_string(s->map().experiences().size()) + " experiences)" +
      (o.localise ? ", localising without growing it" : ", localising before growing it"));
  return s;
}

// The newest usable checkpoint in `store`, or null when it holds none.
std::unique_ptr<slam::VitaSlam> resume(const slam::SlamParams& params, const RobotGeometry& robot,
                                       CheckpointStore& store, const StartupLog& log) {
  std::vector<std::string> problems;
  std::unique_ptr<slam::VitaSlam> resumed;
  std::optional<Checkpoint> cp;
  try {
    cp = store.load_newest(&problems, [&](const Checkpoint& c) {
      resumed = std::make_unique<slam::VitaSlam>(slam::VitaSlam::deserialise(c.payload, params, robot));
    });
  } catch (const CheckpointError& e) {
    // Intact but not loadable here: starting a new map would rotate it out. The operator decides.
    throw std::runtime_error(std::string("cannot resume from ") + e.what() + " (to keep that map, move it out of " +
                             store.directory() +
                             " first; then start with --fresh for a new map, whose checkpoints rotate the "
                             "older ones out)");
  }
  for (const auto& p : problems) log(LogLevel::kWarning, "skipped unusable checkpoint " + p);
  if (!cp) return nullptr;
  // The robot may have been moved while slamd was down: if its odometry resumes long after the
  // checkpoint's, where it was left is only the first candidate.
  resumed->localise_if_moved_for(params.localisation.resume_gap_s);
  log(LogLevel::kInfo, "resuming from " + cp->path + " (after cycle " + std::to_string(cp->sequence) + ")");
  return resumed;
}

}  // namespace

std::unique_ptr<slam::VitaSlam> start_slam(const slam::SlamParams& params, const RobotGeometry& robot,
                                           const StartupOptions& options, CheckpointStore* store,
                                           const StartupLog& log) {
  if (!options.map_file.empty()) return load_map(params, robot, options, store, log);
  if (store != nullptr) {
    for (const auto& f : store->removed_temp_files()) log(LogLevel::kWarning, "removed " + f + " (an unfinished write)");
  }
  if (store != nullptr && !options.fresh) {
    if (auto resumed = resume(params, robot, *store, log)) return resumed;
  }
  return std::make_unique<slam::VitaSlam>(params, robot);
}

void checkpoint_every(SlamNode& node, int every, std::function<void()> checkpoint) {
  if (every <= 0) return;
  node.set_cycle_hook([&node, every, checkpoint = std::move(checkpoint)](const slam::CycleResult&) {
    if (node.counters().cycles % every == 0) checkpoint();
  });
}

}  // namespace whiskeye::slamd
