// What each plot shows, as FigurePanel items in the plot frame (figure.h draws and writes them; the
// world under a run is drawn by world_plots.h, as vita-sim draws it).
#include "plots.h"

#include "whiskeye/figure/figure.h"
#include "whiskeye/sim/world_plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

namespace whiskeye::eval {

namespace {

using figure::Figure;
using figure::FigurePanel;
using figure::LegendEntry;
using figure::Rgb;
using figure::time_colour;
using figure::Xy;

const Rgb kGrey{170, 170, 170};     // ground truth
const Rgb kBlue{30, 110, 200};      // links, sparse experiences
const Rgb kPink{240, 150, 190};     // links the back end revoked
const Rgb kOrange{255, 140, 0};     // dense experiences
const Rgb kGreen{40, 160, 40};      // correct re-localisation
const Rgb kAmber{235, 150, 0};      // neighbour miss: wrong by the paper, within the false-closure tolerance
const Rgb kRed{220, 40, 40};        // false closure
const Rgb kMagenta{190, 0, 190};    // re-localisation, correctness unknown (no ground truth)
const Rgb kSearching{120, 60, 170}; // the path driven before the first correct localisation
const Rgb kLocalisingBand{255, 220, 120};  // under the path while the run reported LOCALISING
const Rgb kLocalisedPath{150, 210, 150};   // the path driven after the first correct localisation
const Rgb kBlack{0, 0, 0};

constexpr double kTrailBreak_m = 0.2;  // consecutive poses further apart: a jump (re-localisation), not a path

Xy at(const Pose2& p) { return {p.x, p.y}; }

double seconds(int64_t from, int64_t to) { return static_cast<double>(to - from) * 1e-6; }

bool has_truth(const EvalInput& input) { return !input.ground_truth.empty(); }

// This log's ground truth in [from, to], one polyline per stretch between kidnaps.
std::vector<std::vector<Xy>> truth_path(const GroundTruth& gt, int64_t from, int64_t to) {
  std::vector<std::vector<Xy>> out(1);
  int64_t prev = from;
  const auto add = [&](const Pose2& p, int64_t utime) {
    if (!out.back().empty() && gt.breaks_between(prev, utime)) out.emplace_back();
    out.back().push_back(at(p));
    prev = utime;
  };
  if (const auto p = gt.at(from)) add(*p, from);
  for (const PoseSample& s : gt.samples()) {
    if (s.utime > from && s.utime < to) add(s.pose, s.utime);
  }
  if (const auto p = gt.at(to)) add(*p, to);
  return out;
}

GroundTruth own_truth(const EvalInput& input) {
  std::vector<int64_t> jumps;
  for (const PoseSample& k : input.kidnaps) jumps.push_back(k.utime);
  return GroundTruth(input.ground_truth, jumps);
}

void draw_ground_truth(FigurePanel& panel, const EvalInput& input) {
  const GroundTruth gt = own_truth(input);  // sorted, one sample per time, broken at the kidnaps
  for (std::vector<Xy>& pts : truth_path(gt, gt.begin_utime(), gt.end_utime())) {
    panel.polyline(std::move(pts), kGrey, 2, "ground-truth");
  }
}

void draw_experience_map(FigurePanel& panel, const EvalInput& input, const Pose2& T) {
  const ExperienceIndex by_id(input.map);
  for (const MapLink& l : input.map.links) {
    const MapExperience* i = by_id.find(l.from_id);
    const MapExperience* j = by_id.find(l.to_id);
    if (i == nullptr || j == nullptr) continue;
    panel.polyline({at(compose(T, i->pose)), at(compose(T, j->pose))}, l.revoked ? kPink : kBlue, 1,
                   l.revoked ? "link revoked" : "link");
  }
  for (const MapExperience& e : input.map.experiences) {
    const Pose2 w = compose(T, e.pose);
    panel.marker(at(w), e.dense ? 5 : 4, e.dense ? kOrange : kBlue, e.dense, e.dense ? "experience dense" : "experience");
    panel.tick(at(w), w.theta, 10, e.dense ? kOrange : kBlue, "heading");
  }
}

// The world (if any) and the ground truth (if any): what every plot of a run starts with.
void draw_scene(FigurePanel& panel, const EvalInput& input, const PlotScene& scene, const Placement& placement) {
  if (scene.world != nullptr) sim::draw_world(panel, *scene.world);
  if (has_truth(input)) draw_ground_truth(panel, input);
  panel.set_frame(placement.frame);
}

void world_legend(Figure& fig, const PlotScene& scene) {
  if (scene.world != nullptr) sim::world_legend(fig);
}

void truth_legend(Figure& fig, const EvalInput& input) {
  if (has_truth(input)) {
    fig.legend({LegendEntry::Kind::Line, kGrey, 2, "ground truth"});
  } else {
    fig.legend({LegendEntry::Kind::Note, kBlack, 0, "no ground truth in this log: no correctness, no errors"});
  }
}

// `revoked`: how many links the back end revoked (their legend entry only where there are any).
void map_legend(Figure& fig, std::size_t revoked) {
  fig.legend({LegendEntry::Kind::Line, kBlue, 1, "link"});
  if (revoked > 0) fig.legend({LegendEntry::Kind::Line, kPink, 1, "link revoked by the back end (" + std::to_string(revoked) + ")"});
  fig.legend({LegendEntry::Kind::Dot, kOrange, 5, "dense experience (contacts)"});
  fig.legend({LegendEntry::Kind::Ring, kBlue, 4, "sparse experience"});
  fig.legend({LegendEntry::Kind::Tick, kBlue, 4, "tick: the experience's heading"});
}

// The estimate before a time: the last VITA_POSE sample before `utime` (the pose a re-localisation
// jumps from), or nothing.
std::optional<Pose2> pose_before(const std::vector<PoseSample>& sorted, int64_t utime) {
  const auto it = std::lower_bound(sorted.begin(), sorted.end(), utime,
                                   [](const PoseSample& s, int64_t t) { return s.utime < t; });
  if (it == sorted.begin()) return std::nullopt;
  return std::prev(it)->pose;
}

std::vector<PoseSample> sorted_estimate(const EvalInput& input) {
  std::vector<PoseSample> s = input.estimate;
  std::stable_sort(s.begin(), s.end(), [](const PoseSample& a, const PoseSample& b) { return a.utime < b.utime; });
  return s;
}

// Re-localisation events (to another experience), in time order.
std::vector<ExperienceEvent> relocalise_events(const EvalInput& input) {
  std::vector<ExperienceEvent> out;
  for (const ExperienceEvent& e : input.events) {
    if (e.type == EventType::kRelocalise && e.to_id != e.from_id) out.push_back(e);
  }
  std::stable_sort(out.begin(), out.end(), [](const ExperienceEvent& a, const ExperienceEvent& b) { return a.utime < b.utime; });
  return out;
}

// The ExM verdict on a re-localisation event, when ground truth gave one.
std::optional<Closure> verdict(const EvalResult& result, const ExperienceEvent& e) {
  for (const Relocalisation& r : result.exm.relocalisations) {
    if (r.utime == e.utime && r.to_id == e.to_id) return r.closure;
  }
  return std::nullopt;
}

Rgb closure_colour(Closure c) { return c == Closure::kCorrect ? kGreen : c == Closure::kNeighbourMiss ? kAmber : kRed; }

// The legend's three verdicts with their counts (indexed by Closure) and the tolerances that part them.
void closure_legend(Figure& fig, LegendEntry::Kind kind, double size, const std::size_t (&n)[3], const EvalParams& p) {
  char text[160];
  std::snprintf(text, sizeof text, "correct: within %g m and %g deg (%zu)", p.correct_position_m,
                rad_to_deg(p.correct_angle_rad), n[0]);
  fig.legend({kind, kGreen, size, text});
  std::snprintf(text, sizeof text, "neighbour miss: wrong, but within %g m and %g deg (%zu)", p.false_closure_position_m,
                rad_to_deg(p.false_closure_angle_rad), n[1]);
  fig.legend({kind, kAmber, size, text});
  std::snprintf(text, sizeof text, "false closure: beyond %g m or %g deg (%zu)", p.false_closure_position_m,
                rad_to_deg(p.false_closure_angle_rad), n[2]);
  fig.legend({kind, kRed, size, text});
}

// When the run reported LOCALISING within [from, to): VITA_POSE's state held until its next sample,
// else VITA_EVENT's.
std::vector<std::pair<int64_t, int64_t>> localising_spans(const EvalInput& input, int64_t from, int64_t to) {
  std::vector<StateSample> states = input.states;
  if (states.empty()) {
    for (const ExperienceEvent& e : input.events) states.push_back({e.utime, e.localising});
  }
  std::stable_sort(states.begin(), states.end(), [](const StateSample& a, const StateSample& b) { return a.utime < b.utime; });
  std::vector<std::pair<int64_t, int64_t>> spans;
  for (std::size_t i = 0; i < states.size(); ++i) {
    if (!states[i].localising) continue;
    const int64_t a = std::max(states[i].utime, from);
    const int64_t b = std::min(i + 1 < states.size() ? states[i + 1].utime : to, to);
    if (b <= a) continue;
    if (!spans.empty() && spans.back().second == a) {
      spans.back().second = b;
    } else {
      spans.emplace_back(a, b);
    }
  }
  return spans;
}

// One panel per localisation instant: where the robot was put down (or started), the path it drove
// while it had not found where it was, the stretches it reported LOCALISING, every false
// localisation, and the first correct one.
void draw_localisation(FigurePanel& panel, const EvalInput& input, const Localisation& l) {
  const GroundTruth gt = own_truth(input);
  const int64_t t0 = l.instant.utime;
  const int64_t found = l.localised ? l.localised_utime : l.window_end_utime;
  for (const auto& [a, b] : localising_spans(input, t0, l.window_end_utime)) {
    for (std::vector<Xy>& pts : truth_path(gt, a, b)) panel.polyline(std::move(pts), kLocalisingBand, 12, "localising");
  }
  // After the localisation the path often goes round again: drawn under the search, which matters.
  if (l.localised) {
    for (std::vector<Xy>& pts : truth_path(gt, found, l.window_end_utime)) {
      panel.polyline(std::move(pts), kLocalisedPath, 2, "localised-path");
    }
  }
  for (std::vector<Xy>& pts : truth_path(gt, t0, found)) panel.polyline(std::move(pts), kSearching, 4, "searching");
  if (l.instant.kind == LocalisationInstant::Kind::kKidnap && l.gt_at) {
    if (const auto before = gt.at(t0 - 1)) {
      panel.polyline({at(*before), at(*l.gt_at)}, kBlack, 1, "kidnap");
      panel.marker(at(*before), 6, kBlack, false, "kidnap-from");
    }
  }
  if (l.gt_at) panel.marker(at(*l.gt_at), 6, kBlack, true, "put-down");
  for (const Relocalisation& f : l.false_events) {
    panel.polyline({at(f.gt_now), at(f.gt_target_created)}, kRed, 2, "false-localisation");
    panel.marker(at(f.gt_target_created), 5, kRed, false, "false-localisation-target");
  }
  if (l.localised) {
    panel.polyline({at(l.gt_localised), at(l.gt_target_created)}, kGreen, 2, "localisation");
    panel.marker(at(l.gt_target_created), 6, kGreen, false, "localisation-target");
    panel.marker(at(l.gt_localised), 9, kGreen, true, "localised");
  }
  panel.set_frame("world frame (ground truth)");
}

std::string localisation_title(const Localisation& l, int64_t origin) {
  char buf[200];
  const double t = seconds(origin, l.instant.utime);
  const char* what = l.instant.kind == LocalisationInstant::Kind::kKidnap ? "kidnap" : "session start";
  if (l.localised) {
    std::snprintf(buf, sizeof buf, "%s at %.1f s: localised after %.2f m (%s laps), %.1f s; %zu false", what, t,
                  *l.distance_m, l.laps ? (std::to_string(std::lround(*l.laps * 100) / 100.0).substr(0, 4)).c_str() : "n/a",
                  *l.time_s, l.false_localisations);
  } else {
    std::snprintf(buf, sizeof buf, "%s at %.1f s: NEVER localised; %zu false", what, t, l.false_localisations);
  }
  return buf;
}

std::vector<std::string> write(const Figure& fig, const std::string& base, const BeforeWrite& before_write) {
  if (before_write) {
    before_write(base + ".png");
    before_write(base + ".svg");
  }
  fig.write_png(base + ".png");
  fig.write_svg(base + ".svg");
  return {base + ".png", base + ".svg"};
}

}  // namespace

Placement place(const EvalInput& input, const EvalResult& result, const PlotScene& scene) {
  if (has_truth(input)) {
    if (result.alignment.valid) return {result.alignment.T_world_map, "world frame (first experience on ground truth)"};
    return {Pose2{}, "map frame, NOT ALIGNED: " + result.alignment.reason};
  }
  std::optional<Pose2> start = scene.start;
  if (!start && scene.world != nullptr) start = scene.world->trajectory.pose_at(0.0);
  const std::vector<PoseSample> est = sorted_estimate(input);
  if (start && !est.empty()) {
    return {compose(*start, inverse(est.front().pose)), "world frame (first pose at the start pose)"};
  }
  return {Pose2{}, "map frame"};
}

std::string plot_stem(const std::string& label) {
  std::string s = label;
  std::replace(s.begin(), s.end(), '#', '-');
  return s;
}

std::vector<std::string> plot_run(const std::string& dir, const PlotRun& run, const PlotScene& scene,
                                  const BeforeWrite& before_write) {
  const std::string base = (std::filesystem::path(dir) / plot_stem(run.label)).string();
  const EvalInput& input = *run.input;
  const EvalResult& result = *run.result;
  const Placement pl = place(input, result, scene);
  const bool truth = has_truth(input);
  std::vector<std::string> written;
  const auto keep = [&](const std::vector<std::string>& paths) { written.insert(written.end(), paths.begin(), paths.end()); };

  {  // The experience map.
    Figure fig(run.label + ": experience map");
    FigurePanel& panel = fig.add_panel(run.label);
    draw_scene(panel, input, scene, pl);
    draw_experience_map(panel, input, pl.T_plot_map);
    world_legend(fig, scene);
    truth_legend(fig, input);
    map_legend(fig, input.map.revoked_links());
    keep(write(fig, base + "_experience_map", before_write));
  }

  const std::vector<PoseSample> est = sorted_estimate(input);
  const std::vector<ExperienceEvent> relocs = relocalise_events(input);

  {  // The pose trail, coloured by time, with the re-localisations on it.
    Figure fig(run.label + ": pose trail and re-localisations");
    FigurePanel& panel = fig.add_panel(run.label);
    draw_scene(panel, input, scene, pl);
    const int64_t t0 = est.empty() ? 0 : est.front().utime;
    const double duration = est.empty() ? 1.0 : std::max(1e-6, seconds(t0, est.back().utime));
    // Pieces of about 1/300 of the run, each in the colour of its middle; points closer than 5 mm
    // merged (a 50 Hz trail is dense); a jump breaks the line.
    const double piece_s = duration / 300.0;
    std::vector<Xy> piece;
    double piece_start = 0.0;
    const auto flush = [&](double t_end) {
      if (piece.size() >= 2) panel.polyline(piece, time_colour(0.5 * (piece_start + t_end) / duration), 2, "trail");
      piece.clear();
    };
    for (const PoseSample& s : est) {
      const Xy p = at(compose(pl.T_plot_map, s.pose));
      const double t = seconds(t0, s.utime);
      if (!piece.empty()) {
        const Xy& last = piece.back();
        const double d = std::hypot(p.x - last.x, p.y - last.y);
        if (d > kTrailBreak_m) {
          flush(t);
          piece_start = t;
        } else if (t - piece_start >= piece_s) {
          piece.push_back(p);
          flush(t);
          piece_start = t;
        } else if (d < 0.005) {
          continue;
        }
      }
      piece.push_back(p);
    }
    flush(duration);
    std::size_t judged[3] = {0, 0, 0};  // by Closure
    int unknown = 0;
    for (const ExperienceEvent& e : relocs) {
      const std::optional<Pose2> before = pose_before(est, e.utime);
      if (!before) continue;
      const std::optional<Closure> v = verdict(result, e);
      if (v) {
        ++judged[static_cast<int>(*v)];
      } else {
        ++unknown;
      }
      panel.marker(at(compose(pl.T_plot_map, *before)), 5, v ? closure_colour(*v) : kMagenta, false, "relocalisation");
    }
    world_legend(fig, scene);
    truth_legend(fig, input);
    fig.legend({LegendEntry::Kind::Line, time_colour(0.5), 2, "pose estimate (VITA_POSE), coloured by time"});
    if (judged[0] + judged[1] + judged[2] > 0 || truth) closure_legend(fig, LegendEntry::Kind::Ring, 5, judged, scene.params);
    if (unknown > 0 || !truth) {
      fig.legend({LegendEntry::Kind::Ring, kMagenta, 5, "re-localisation (" + std::to_string(unknown) + ")"});
    }
    fig.legend({LegendEntry::Kind::Note, kBlack, 0, "ring: the estimate just before the event"});
    fig.colour_bar({"time since the first pose (s)", 0.0, duration});
    keep(write(fig, base + "_trail", before_write));
  }

  {  // The re-localisations.
    Figure fig(run.label + ": re-localisations");
    FigurePanel& panel = fig.add_panel(run.label);
    draw_scene(panel, input, scene, pl);
    world_legend(fig, scene);
    truth_legend(fig, input);
    if (truth) {
      // Where the robot was and where the target was created, by ground truth. Correct ones first,
      // false closures last, so that the worse stay visible over the better.
      std::size_t judged[3] = {0, 0, 0};  // by Closure
      for (Closure pass : {Closure::kCorrect, Closure::kNeighbourMiss, Closure::kFalse}) {
        for (const Relocalisation& r : result.exm.relocalisations) {
          if (r.closure != pass) continue;
          const Rgb c = closure_colour(r.closure);
          panel.polyline({at(r.gt_now), at(r.gt_target_created)}, c, 2,
                         std::string("relocalisation ") + closure_name(r.closure));
          panel.marker(at(r.gt_now), 4, c, true, "relocalisation-from");
          panel.marker(at(r.gt_target_created), 4, c, false, "relocalisation-target");
          ++judged[static_cast<int>(r.closure)];
        }
      }
      closure_legend(fig, LegendEntry::Kind::Line, 2, judged, scene.params);
      fig.legend({LegendEntry::Kind::Dot, kBlack, 4, "robot at the event (ground truth)"});
      fig.legend({LegendEntry::Kind::Ring, kBlack, 4, "where the target was created (ground truth)"});
    } else {
      // Without truth: the jump each re-localisation made in the map, from the estimate before it to
      // the target experience. A long jump is a loop closure to read against the scene.
      std::size_t n = 0;
      for (const ExperienceEvent& e : relocs) {
        const std::optional<Pose2> before = pose_before(est, e.utime);
        const MapExperience* target = input.map.find(e.to_id);
        if (!before || target == nullptr) continue;
        const Xy a = at(compose(pl.T_plot_map, *before));
        const Xy b = at(compose(pl.T_plot_map, target->pose));
        panel.polyline({a, b}, kMagenta, 2, "relocalisation");
        panel.marker(a, 3, kMagenta, true, "relocalisation-from");
        panel.marker(b, 7, kMagenta, false, "relocalisation-target");
        ++n;
      }
      fig.legend({LegendEntry::Kind::Line, kMagenta, 2, "re-localisation: the jump in the map (" + std::to_string(n) + ")"});
      fig.legend({LegendEntry::Kind::Dot, kMagenta, 3, "estimate just before the event"});
      fig.legend({LegendEntry::Kind::Ring, kMagenta, 7, "the target experience (final map)"});
    }
    keep(write(fig, base + "_relocalisations", before_write));
  }

  if (result.localisation && !result.localisation->instants.empty()) {  // Kidnaps and session starts.
    const int64_t origin = run_start_utime(input);
    Figure fig(run.label + ": localisation after each kidnap or session start");
    for (const Localisation& l : result.localisation->instants) {
      FigurePanel& panel = fig.add_panel(localisation_title(l, origin));
      if (scene.world != nullptr) sim::draw_world(panel, *scene.world);
      draw_ground_truth(panel, input);
      draw_localisation(panel, input, l);
    }
    world_legend(fig, scene);
    fig.legend({LegendEntry::Kind::Line, kGrey, 2, "ground truth"});
    fig.legend({LegendEntry::Kind::Ring, kBlack, 6, "kidnap: picked up (ring), put down (dot); or the session's start"});
    fig.legend({LegendEntry::Kind::Line, kSearching, 3, "driven before the first correct localisation"});
    fig.legend({LegendEntry::Kind::Line, kLocalisingBand, 12, "slamd reported LOCALISING"});
    fig.legend({LegendEntry::Kind::Line, kRed, 2, "false localisation: to where its target was made"});
    fig.legend({LegendEntry::Kind::Dot, kGreen, 9, "first correct localisation (and its target, ring)"});
    fig.legend({LegendEntry::Kind::Line, kLocalisedPath, 2, "driven after it"});
    fig.share_axes(true);
    keep(write(fig, base + "_localisation", before_write));
  }
  return written;
}

std::vector<std::string> plot_comparison(const std::string& dir, const std::vector<PlotRun>& runs,
                                         const PlotScene& scene, const BeforeWrite& before_write) {
  Figure fig("experience maps side by side");
  bool any_truth = false;
  std::size_t revoked = 0;
  for (const PlotRun& run : runs) {
    revoked += run.input->map.revoked_links();
    const Placement pl = place(*run.input, *run.result, scene);
    FigurePanel& panel = fig.add_panel(run.label);
    draw_scene(panel, *run.input, scene, pl);
    draw_experience_map(panel, *run.input, pl.T_plot_map);
    any_truth = any_truth || has_truth(*run.input);
  }
  world_legend(fig, scene);
  if (any_truth) fig.legend({LegendEntry::Kind::Line, kGrey, 2, "ground truth"});
  map_legend(fig, revoked);
  fig.share_axes(true);
  return write(fig, (std::filesystem::path(dir) / "comparison").string(), before_write);
}

}  // namespace whiskeye::eval
