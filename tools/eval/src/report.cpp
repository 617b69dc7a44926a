// Formats the metrics as a Table-I-like table and as JSON (undefined values: "n/a" / null).
#include "report.h"

#include "whiskeye/common/utime.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace whiskeye::eval {

std::optional<PaperRow> paper_row(const std::string& name) {
  // Table I of the paper, copied from ../shared/design/metrics.md.
  if (name == "visual") return PaperRow{"paper Visual-SLAM", 4.4024, 0.121, 0.0, 0.9168, 0.6776, 1.8872, 8.4155};
  if (name == "tactile") return PaperRow{"paper Tactile-SLAM", 3.8129, 0.4643, 0.0, 1.1739, 1.2901, 1.5604, 3.0061};
  if (name == "vita") return PaperRow{"paper ViTa-SLAM", 0.4311, 0.7778, 1.0, 0.1445, 0.0474, 0.6404, 3.8371};
  return std::nullopt;
}

namespace {

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

// What a cell that needs ground truth says in a run without it.
const char* const kNoTruth = "n/a — no ground truth";

std::string opt(const std::optional<double>& v, const char* format = "%.4f") {
  return v ? fmt(format, *v) : std::string("n/a");
}

std::string lem_cell(const std::optional<LemResult>& lem, bool position) {
  if (!lem || lem->samples_used == 0) return "n/a";
  const ErrorStats& s = position ? lem->position_m : lem->orientation_rad;
  return fmt("%.4f", s.rmse) + " (" + fmt("%.4f", s.mean_abs) + " ± " + fmt("%.4f", s.std_abs) + ")";
}

// Pads to a width counted in code points ("±" is two bytes in UTF-8).
std::string pad(const std::string& s, std::size_t width) {
  std::size_t cps = 0;
  for (unsigned char c : s) cps += (c & 0xC0) != 0x80;
  return s + std::string(cps < width ? width - cps : 0, ' ');
}

std::string padded_row(const std::vector<std::string>& cells, const std::vector<std::size_t>& widths) {
  std::string out;
  for (std::size_t i = 0; i < cells.size(); ++i) out += pad(cells[i], widths[i]) + (i + 1 < cells.size() ? " " : "");
  while (!out.empty() && out.back() == ' ') out.pop_back();
  return out + "\n";
}

std::string row(const std::vector<std::string>& cells) { return padded_row(cells, {22, 9, 8, 8, 8, 9, 30, 30}); }

std::string ate_cell(const AteResult& ate) { return ate.position_m ? fmt("%.4f", ate.position_m->rmse) : "n/a"; }

std::string localisation_row(const std::vector<std::string>& cells) {
  return padded_row(cells, {22, 9, 10, 8, 9, 7, 9, 11, 10});
}

nlohmann::json opt_json(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

nlohmann::json pose_json(const Pose2& p) { return {{"x", p.x}, {"y", p.y}, {"theta", p.theta}}; }

nlohmann::json alignment_json(const Alignment& a) {
  nlohmann::json j = {{"valid", a.valid}};
  if (a.valid) {
    j["T_world_map"] = pose_json(a.T_world_map);
  } else {
    j["reason"] = a.reason;
  }
  return j;
}

nlohmann::json stats_json(const ErrorStats& s) {
  return {{"rmse", s.rmse}, {"mean_abs", s.mean_abs}, {"std_abs", s.std_abs}};
}

nlohmann::json links_json(const LinkJudgement& l) {
  return {{"judged", l.judged},
          {"wrong", l.wrong},
          {"wrong_kept", l.wrong_kept},
          {"right_revoked", l.right_revoked},
          {"worst_kept_m", opt_json(l.worst_kept_m)}};
}

nlohmann::json ate_json(const AteResult& a) {
  nlohmann::json windows = nlohmann::json::array();
  for (const AteWindow& w : a.windows) {
    windows.push_back({{"from_lap", w.from_lap},
                       {"to_lap", w.to_lap},
                       {"begin_utime", w.begin_utime},
                       {"end_utime", w.end_utime},
                       {"samples", w.samples},
                       {"rmse_m", w.rmse},
                       {"rmse_own_fit_m", opt_json(w.rmse_own_fit)}});
  }
  nlohmann::json position = nullptr;
  if (a.position_m) {
    position = {{"rmse", a.position_m->rmse},
                {"mean", a.position_m->mean},
                {"median", a.position_m->median},
                {"max", a.position_m->max}};
  }
  return {{"samples_used", a.samples_used},
          {"samples_outside_gt", a.samples_outside_gt},
          {"samples_localising", a.samples_localising},
          {"alignment", alignment_json(a.alignment)},
          {"position_m", position},
          {"lap_length_m", opt_json(a.lap_length_m)},
          {"window_laps", a.window_laps},
          {"windows", windows}};
}

nlohmann::json lem_json(const std::optional<LemResult>& lem) {
  if (!lem) return nullptr;
  // No sample inside the ground truth's time range: no error was measured, which is not zero error.
  const bool measured = lem->samples_used > 0;
  return {{"samples_used", lem->samples_used},
          {"samples_outside_gt", lem->samples_outside_gt},
          {"position_m", measured ? stats_json(lem->position_m) : nlohmann::json(nullptr)},
          {"orientation_rad", measured ? stats_json(lem->orientation_rad) : nlohmann::json(nullptr)}};
}

// `judged`: false for a run without ground truth, whose fields that judge correctness are null.
nlohmann::json exm_json(const ExmResult& x, bool judged) {
  const auto judging = [judged](nlohmann::json v) { return judged ? std::move(v) : nlohmann::json(nullptr); };
  nlohmann::json relocs = nlohmann::json::array();
  for (const Relocalisation& r : x.relocalisations) {
    relocs.push_back({{"utime", r.utime},
                      {"from_id", r.from_id},
                      {"to_id", r.to_id},
                      {"position_error_m", r.position_error_m},
                      {"angle_error_rad", r.angle_error_rad},
                      {"correct", r.correct},
                      {"closure", closure_name(r.closure)},
                      {"after_base_set", r.after_base_set}});
  }
  return {{"arr", opt_json(x.arr)},
          {"arcr", opt_json(x.arcr)},
          {"arcr_after_base", opt_json(x.arcr_after_base)},
          {"false_closures", judging(x.false_closures)},
          {"false_closure_worst_m", opt_json(x.false_closure_worst_m)},
          {"neighbour_misses", judging(x.neighbour_misses)},
          {"neighbour_miss_share", opt_json(x.neighbour_miss_share)},
          {"experience_spacing",
           judging({{"steps", x.spacing_steps},
                    {"median_m", opt_json(x.spacing_median_m)},
                    {"median_heading_deg", x.spacing_median_heading_rad
                                               ? nlohmann::json(rad_to_deg(*x.spacing_median_heading_rad))
                                               : nlohmann::json(nullptr)}})},
          {"valid_fraction", opt_json(x.valid_fraction)},
          {"base_end_found", x.base_end_found},
          {"base_end_utime", x.base_end_found ? nlohmann::json(x.base_end_utime) : nlohmann::json(nullptr)},
          {"base_end_s", x.base_end_found ? nlohmann::json(x.base_end_s) : nlohmann::json(nullptr)},
          {"base_set_size", x.base_set_size},
          {"experience_events_after_base", x.experience_events_after_base},
          {"relocalisations_after_base", x.relocalisations_after_base},
          {"correct_after_base", judging(x.correct_after_base)},
          {"relocalisations_total", x.relocalisations_total},
          {"correct_total", judging(x.correct_total)},
          {"experiences_created", x.experiences_created},
          {"valid_experiences", judging(x.valid_experiences)},
          {"events_outside_gt", judging(x.events_outside_gt)},
          {"relocalise_unknown_target", x.relocalise_unknown_target},
          {"relocalise_to_current", x.relocalise_to_current},
          {"relocalisations", judging(relocs)}};
}

nlohmann::json localisation_json(const std::optional<LocalisationReport>& report, int64_t origin) {
  if (!report) return nullptr;
  const auto deg = [](const std::optional<double>& rad) {
    return rad ? nlohmann::json(rad_to_deg(*rad)) : nlohmann::json(nullptr);
  };
  nlohmann::json instants = nlohmann::json::array();
  for (const Localisation& l : report->instants) {
    nlohmann::json falses = nlohmann::json::array();
    for (const Relocalisation& f : l.false_events) {
      falses.push_back({{"utime", f.utime},
                        {"to_id", f.to_id},
                        {"position_error_m", f.position_error_m},
                        {"angle_error_deg", rad_to_deg(f.angle_error_rad)}});
    }
    instants.push_back(
        {{"kind", instant_name(l.instant.kind)},
         {"utime", l.instant.utime},
         {"t_s", utime_delta_seconds(origin, l.instant.utime)},
         {"pose", l.gt_at ? pose_json(*l.gt_at) : nlohmann::json(nullptr)},
         {"window_end_s", utime_delta_seconds(origin, l.window_end_utime)},
         {"localised", l.localised},
         {"localised_utime", l.localised ? nlohmann::json(l.localised_utime) : nlohmann::json(nullptr)},
         {"localised_to_id", l.localised ? nlohmann::json(l.localised_by.to_id) : nlohmann::json(nullptr)},
         {"localised_error_m", l.localised ? nlohmann::json(l.position_error_m) : nlohmann::json(nullptr)},
         {"localised_error_deg", l.localised ? nlohmann::json(rad_to_deg(l.angle_error_rad)) : nlohmann::json(nullptr)},
         {"time_to_localise_s", opt_json(l.time_s)},
         {"distance_to_localise_m", opt_json(l.distance_m)},
         {"laps_to_localise", opt_json(l.laps)},
         {"false_localisations", l.false_localisations},
         {"false_localisation_events", falses},
         {"localising_s", l.localising_s},
         {"lem_after_m", opt_json(l.lem_after_m)},
         {"lem_after_deg", deg(l.lem_after_angle_rad)},
         {"lem_after_events", l.lem_events},
         {"judged_events", l.judged_events},
         {"unjudged_events", l.unjudged_events}});
  }
  return {{"lap_length_m", opt_json(report->lap_length_m)},
          {"instants", instants},
          {"summary",
           {{"instants", report->instants.size()},
            {"localised", report->localised},
            {"within_one_lap", report->within_one_lap},
            {"within_two_laps", report->within_two_laps},
            {"worst_laps", opt_json(report->worst_laps)},
            {"false_localisations", report->false_localisations},
            {"false_localisations_max", report->false_localisations_max},
            {"with_false_localisation", report->with_false_localisation},
            {"localising_s", report->localising_s},
            {"lem_after_m", opt_json(report->lem_after_m)},
            {"lem_after_events", report->lem_events}}}};
}

// The localisation block of a run: a line per instant.
void localisation_block(std::ostringstream& out, const LocalisationReport& l, int64_t origin) {
  out << "  localisation (after a kidnap or a session start; lap " << opt(l.lap_length_m, "%.3f")
      << " m by ground truth): " << l.localised << " of " << l.instants.size() << " localised, "
      << l.false_localisations << " false localisations\n";
  for (const Localisation& i : l.instants) {
    out << "    " << instant_name(i.instant.kind) << " at " << fmt("%.3f", utime_delta_seconds(origin, i.instant.utime))
        << " s: ";
    if (i.localised) {
      out << "localised after " << fmt("%.2f", *i.time_s) << " s, " << fmt("%.2f", *i.distance_m) << " m ("
          << opt(i.laps, "%.2f") << " laps) onto experience " << i.localised_by.to_id << " ("
          << fmt("%.3f", i.position_error_m) << " m, " << fmt("%.1f", rad_to_deg(i.angle_error_rad)) << " deg off)";
    } else {
      out << "never localised (up to " << fmt("%.3f", utime_delta_seconds(origin, i.window_end_utime)) << " s)";
    }
    out << "; " << i.false_localisations << " false localisations";
    for (std::size_t k = 0; k < i.false_events.size() && k < 5; ++k) {
      out << (k == 0 ? " (" : ", ") << fmt("%.2f", i.false_events[k].position_error_m) << " m";
    }
    if (!i.false_events.empty()) out << (i.false_events.size() > 5 ? ", ...)" : ")");
    out << "; LOCALISING " << fmt("%.2f", i.localising_s) << " s";
    if (i.localised) out << "; LEM after " << opt(i.lem_after_m, "%.3f") << " m over " << i.lem_events << " events";
    out << "\n";
  }
}

// ATE's figures, its alignment and its windows of laps.
void ate_block(std::ostringstream& out, const AteResult& a) {
  if (!a.position_m) {
    out << "  ATE: none (" << a.alignment.reason << ")";
  } else {
    const AteStats& p = *a.position_m;
    const Pose2& t = a.alignment.T_world_map;
    out << "  ATE (best-fit SE(2) alignment T_world_map = (" << fmt("%.4f", t.x) << ", " << fmt("%.4f", t.y) << ", "
        << fmt("%.4f", t.theta) << " rad)): RMSE " << fmt("%.4f", p.rmse) << " m, mean " << fmt("%.4f", p.mean)
        << ", median " << fmt("%.4f", p.median) << ", max " << fmt("%.4f", p.max) << " m";
  }
  out << "; " << a.samples_used << " samples, " << a.samples_localising << " excluded while LOCALISING, "
      << a.samples_outside_gt << " outside the ground truth\n";
  if (a.windows.size() > 1) {
    out << "  ATE per " << fmt("%g", a.window_laps) << " laps (lap " << opt(a.lap_length_m, "%.3f")
        << " m), RMSE under the run's alignment / the window's own:";
    for (const AteWindow& w : a.windows) {
      out << " [" << fmt("%.1f", w.from_lap) << "-" << fmt("%.1f", w.to_lap) << "] " << fmt("%.3f", w.rmse) << "/"
          << opt(w.rmse_own_fit, "%.3f");
    }
    out << "\n";
  }
}

nlohmann::json enm_json(const EnmResult& e) {
  return {{"enm", opt_json(e.enm)},
          {"translation_m2", opt_json(e.translation)},
          {"rotation_rad2", opt_json(e.rotation)},
          {"links_used", e.links_used},
          {"links_excluded", e.links_excluded}};
}

}  // namespace

std::string format_table(const std::vector<RunReport>& runs, const EvalParams& params,
                         const std::vector<PaperRow>& paper) {
  std::ostringstream out;
  out << row({"method", "EnM", "ARR", "ARCR", "false", "ATE (m)", "paper's LEM pos (m)", "paper's LEM ori (rad)"});
  out << row({"", "", "", "", "closures", "RMSE", "RMSE (mean|e| ± std|e|)", "RMSE (mean|e| ± std|e|)"});
  out << std::string(131, '-') << "\n";
  for (const RunReport& r : runs) {
    const EvalResult& e = r.result;
    if (!e.ground_truth) {
      out << row({r.label, "n/a", opt(e.exm.arr), "n/a", "n/a", "n/a", kNoTruth, kNoTruth});
      continue;
    }
    out << row({r.label, opt(e.enm.enm), opt(e.exm.arr), opt(e.exm.arcr), std::to_string(e.exm.false_closures),
                ate_cell(e.ate), lem_cell(e.lem, true), lem_cell(e.lem, false)});
  }
  for (const PaperRow& p : paper) {
    out << row({p.method, fmt("%.4f", p.enm), fmt("%.4f", p.arr), fmt("%.4f", p.arcr), "n/a", "n/a",
                fmt("%.4f", p.lem_pos) + " ± " + fmt("%.4f", p.lem_pos_spread),
                fmt("%.4f", p.lem_ori) + " ± " + fmt("%.4f", p.lem_ori_spread)});
  }
  out << "\n";
  bool any_localisation = false;
  for (const RunReport& r : runs) any_localisation = any_localisation || r.result.localisation;
  if (any_localisation) {
    out << localisation_row({"localisation", "instants", "localised", "<=1 lap", "<=2 laps", "worst", "false",
                             "LOCALISING", "LEM after"});
    out << localisation_row({"", "", "", "", "", "laps", "localis.", "(s)", "loc. (m)"});
    out << std::string(112, '-') << "\n";
    for (const RunReport& r : runs) {
      if (!r.result.localisation) continue;
      const LocalisationReport& l = *r.result.localisation;
      out << localisation_row({r.label, std::to_string(l.instants.size()), std::to_string(l.localised),
                               std::to_string(l.within_one_lap), std::to_string(l.within_two_laps),
                               opt(l.worst_laps, "%.2f"), std::to_string(l.false_localisations),
                               fmt("%.1f", l.localising_s), opt(l.lem_after_m, "%.3f")});
    }
    out << "\n";
  }
  for (const RunReport& r : runs) {
    const EvalResult& e = r.result;
    out << r.label << " (" << r.path << "):\n";
    out << "  samples: " << r.pose_samples << " VITA_POSE, " << r.events << " VITA_EVENT, "
        << r.ground_truth_samples << " GROUND_TRUTH; final map " << r.map_experiences << " experiences, "
        << r.map_links << " links (" << r.map_links_revoked << " revoked by the back end)\n";
    for (const auto& [ch, n] : r.decode_errors) out << "  undecodable messages on " << ch << ": " << n << "\n";
    if (!r.faults.empty()) {
      out << "  simulated faults (SIM_FAULT):";
      for (const FaultEvent& f : r.faults) {
        if (f.active) out << " " << f.name << ";";
      }
      out << "\n";
    }
    if (!r.log_damage.empty()) out << "  damaged log: " << r.log_damage << "\n";
    if (!e.ground_truth) {
      const ExmResult& x = e.exm;
      out << "  no ground truth (no GROUND_TRUTH in the log): EnM, ARCR, ATE, LEM and the valid fraction are "
             "unavailable; events counted, none judged\n";
      out << "  ExM counts: " << x.experiences_created << " new experiences, " << x.relocalisations_total
          << " re-localisations (correctness unknown)";
      if (x.base_end_found) {
        out << "; after a base set of " << fmt("%.3f", x.base_end_s) << " s (" << x.base_set_size
            << " experiences): " << x.experience_events_after_base << " experience events, "
            << x.relocalisations_after_base << " re-localisations, ARR " << opt(x.arr);
      } else {
        out << "; ARR needs --base-duration without ground truth";
      }
      out << "\n";
      continue;
    }
    ate_block(out, e.ate);
    const LinkJudgement& lj = e.links;
    out << "  links against the truth (alignment-free): " << lj.judged << " judged, " << lj.wrong
        << " wrong (beyond the false-closure tolerance), " << lj.wrong_kept << " of them kept; " << lj.right_revoked
        << " right ones revoked; worst kept " << opt(lj.worst_kept_m, "%.3f") << " m\n";
    if (e.alignment.valid) {
      const Pose2& t = e.alignment.T_world_map;
      out << "  the paper's LEM: alignment (first experience onto ground truth) T_world_map = (" << fmt("%.4f", t.x)
          << ", " << fmt("%.4f", t.y) << ", " << fmt("%.4f", t.theta) << " rad)";
      if (e.lem) {
        out << "; " << e.lem->samples_used << " samples, " << e.lem->samples_outside_gt
            << " excluded (outside the ground-truth time range)";
      }
      out << "\n";
    } else {
      out << "  the paper's LEM: no alignment (" << e.alignment.reason << "); not computed\n";
    }
    const ExmResult& x = e.exm;
    out << "  ExM: base set " << x.base_set_size << " experiences ("
        << (x.base_end_found ? "until " + fmt("%.3f", x.base_end_s) + " s after the first ground truth"
                             : std::string("revolution never completed: all are base"))
        << "); after it " << x.experience_events_after_base << " experience events, "
        << x.relocalisations_after_base << " re-localisations, " << x.correct_after_base << " correct\n";
    out << "       all re-localisations incl. base set (ARCR's): " << x.relocalisations_total << ", correct "
        << x.correct_total << "; valid experiences " << x.valid_experiences << "/" << x.experiences_created
        << " = " << opt(x.valid_fraction) << "\n";
    out << "       of the " << x.relocalisations_total - x.correct_total << " wrong (beyond "
        << fmt("%g", params.correct_position_m) << " m or " << fmt("%g", rad_to_deg(params.correct_angle_rad))
        << " deg): " << x.false_closures << " false closures (target beyond "
        << fmt("%g", params.false_closure_position_m) << " m or " << fmt("%g", rad_to_deg(params.false_closure_angle_rad))
        << " deg; worst " << opt(x.false_closure_worst_m, "%.3f") << " m), " << x.neighbour_misses
        << " neighbour misses (share " << opt(x.neighbour_miss_share, "%.3f") << ")\n";
    out << "       experience spacing (ground truth, " << x.spacing_steps << " steps to a new experience): median "
        << opt(x.spacing_median_m, "%.3f") << " m, "
        << opt(x.spacing_median_heading_rad ? std::optional<double>(rad_to_deg(*x.spacing_median_heading_rad))
                                            : std::nullopt,
               "%.2f")
        << " deg\n";
    if (x.events_outside_gt + x.relocalise_unknown_target + x.relocalise_to_current > 0) {
      out << "       not counted: " << x.events_outside_gt << " outside ground truth, "
          << x.relocalise_unknown_target << " to an unknown experience, " << x.relocalise_to_current
          << " to the current experience\n";
    }
    out << "  EnM: " << opt(e.enm.enm) << " = translation " << opt(e.enm.translation) << " m² + rotation "
        << opt(e.enm.rotation) << " rad² over " << e.enm.links_used << " links (" << e.enm.links_excluded
        << " excluded)\n";
    if (e.localisation) localisation_block(out, *e.localisation, r.start_utime);
  }
  return out.str();
}

nlohmann::json to_json(const std::vector<RunReport>& runs, const EvalParams& params,
                       const std::vector<PaperRow>& paper) {
  nlohmann::json j;
  j["params"] = {{"correct_position_m", params.correct_position_m},
                 {"correct_angle_rad", params.correct_angle_rad},
                 {"false_closure_position_m", params.false_closure_position_m},
                 {"false_closure_angle_rad", params.false_closure_angle_rad},
                 {"centre", {params.centre_x, params.centre_y}},
                 {"ate_window_laps", params.ate_window_laps},
                 {"base_duration_s", opt_json(params.base_duration_s)}};
  j["runs"] = nlohmann::json::array();
  for (const RunReport& r : runs) {
    const EvalResult& e = r.result;
    nlohmann::json decode = nlohmann::json::object();
    for (const auto& [ch, n] : r.decode_errors) decode[ch] = n;
    nlohmann::json faults = nlohmann::json::array();
    for (const FaultEvent& f : r.faults) faults.push_back({{"utime", f.utime}, {"fault", f.name}, {"active", f.active}});
    j["runs"].push_back({{"label", r.label},
                         {"input", r.path},
                         {"mode", r.mode},
                         {"counts",
                          {{"pose_samples", r.pose_samples},
                           {"events", r.events},
                           {"map_experiences", r.map_experiences},
                           {"map_links", r.map_links},
                           {"map_links_revoked", r.map_links_revoked},
                           {"ground_truth_samples", r.ground_truth_samples}}},
                         {"decode_errors", decode},
                         {"faults", faults},
                         {"log_damage", r.log_damage.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.log_damage)},
                         {"ate", e.ground_truth ? ate_json(e.ate) : nlohmann::json(nullptr)},
                         {"alignment", alignment_json(e.alignment)},
                         {"lem", lem_json(e.lem)},
                         {"ground_truth", e.ground_truth},
                         {"unavailable", e.ground_truth ? nlohmann::json(nullptr)
                                                        : nlohmann::json("no ground truth: no GROUND_TRUTH in the log")},
                         {"exm", exm_json(e.exm, e.ground_truth)},
                         {"links", e.ground_truth ? links_json(e.links) : nlohmann::json(nullptr)},
                         {"localisation", localisation_json(e.localisation, r.start_utime)},
                         {"enm", e.ground_truth ? enm_json(e.enm)
                                                : nlohmann::json({{"enm", nullptr},
                                                                  {"translation_m2", nullptr},
                                                                  {"rotation_rad2", nullptr},
                                                                  {"links_used", nullptr},
                                                                  {"links_excluded", nullptr}})}});
  }
  j["paper_rows"] = nlohmann::json::array();
  for (const PaperRow& p : paper) {
    j["paper_rows"].push_back({{"method", p.method},
                               {"enm", p.enm},
                               {"arr", p.arr},
                               {"arcr", p.arcr},
                               {"lem_pos", {p.lem_pos, p.lem_pos_spread}},
                               {"lem_ori", {p.lem_ori, p.lem_ori_spread}}});
  }
  return j;
}

std::string format_tum(const std::vector<PoseSample>& poses) {
  std::ostringstream out;
  out << "# timestamp x y z qx qy qz qw\n";
  char line[192];
  for (const PoseSample& p : poses) {
    const int64_t whole = p.utime / 1000000;
    int64_t micro = p.utime % 1000000;
    // Written from the integer utime: a double's seconds since 1970 would lose the microseconds.
    const bool negative = p.utime < 0;
    if (micro < 0) micro = -micro;
    std::snprintf(line, sizeof line, "%s%lld.%06lld %.9g %.9g 0 0 0 %.9g %.9g\n", negative && whole == 0 ? "-" : "",
                  static_cast<long long>(whole), static_cast<long long>(micro), p.pose.x, p.pose.y,
                  std::sin(p.pose.theta / 2.0), std::cos(p.pose.theta / 2.0));
    out << line;
  }
  return out.str();
}

std::string format_trace_csv(const std::vector<CycleTrace>& rows) {
  std::ostringstream out;
  out << "cycle,t_s,event,from_id,to_id,gt_x,gt_y,gt_theta,target_error_m,target_error_deg,correct,after_base_set,closure,"
         "template_id,template_new,error,visual_error,pfh_error,sda_error,visual_shift,visual_used,tactile_used,"
         "active_faults,localisation,localisation_marks\n";
  const auto g = [](double v) { return fmt("%.6g", v); };
  for (const CycleTrace& r : rows) {
    const ExperienceEvent& e = r.event;
    const char* type = e.type == EventType::kNewExperience ? "new" : e.type == EventType::kRelocalise ? "relocalise" : "same";
    out << e.cycle << ',' << fmt("%.3f", r.t_s) << ',' << type << ',' << e.from_id << ',' << e.to_id << ',';
    if (r.gt) {
      out << g(r.gt->x) << ',' << g(r.gt->y) << ',' << g(r.gt->theta) << ',';
    } else {
      out << ",,,";
    }
    if (r.relocalisation) {
      const Relocalisation& rl = *r.relocalisation;
      out << g(rl.position_error_m) << ',' << g(rad_to_deg(rl.angle_error_rad)) << ',' << (rl.correct ? 1 : 0) << ','
          << (rl.after_base_set ? 1 : 0) << ',' << closure_name(rl.closure) << ',';
    } else {
      out << ",,,,,";
    }
    if (r.match) {
      const TemplateMatch& m = *r.match;
      out << m.template_id << ',' << (m.is_new ? 1 : 0) << ',' << g(m.error) << ',' << g(m.visual_error) << ','
          << g(m.pfh_error) << ',' << g(m.sda_error) << ',' << m.visual_shift << ',' << (m.visual_used ? 1 : 0) << ','
          << (m.tactile_used ? 1 : 0);
    } else {
      out << ",,,,,,,,";
    }
    out << ',';
    for (std::size_t i = 0; i < r.active_faults.size(); ++i) out << (i ? ";" : "") << r.active_faults[i];
    out << ',' << (e.localising ? "localising" : "tracking") << ',';
    for (std::size_t i = 0; i < r.localisation_marks.size(); ++i) out << (i ? ";" : "") << r.localisation_marks[i];
    out << '\n';
  }
  return out.str();
}

}  // namespace whiskeye::eval
