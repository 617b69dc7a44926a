"""The one summary of both executors: suite.json, suite.md and the plots from the worlds' records;
the progress lines and the summary on the terminal."""
import os
import shlex
import sys
import threading
import time

from .cli import executor_options, world_options
from .common import METRICS, MODES, ROOT, SCRIPT, WRONG_CLOSURE_KINDS, file_digest, fmt, world_seed, write_json
from .plots import write_plots
from .stats import distribution, percentile
from .targets import (FOOLED_ARCR, FOOLED_ENM_RATIO, check_localisation_targets, check_outlier_targets,
                      check_long_targets, check_targets, fooled, fooled_where_fusion_is_not, localisation_summary,
                      long_summary, miss_lines, outlier_ratio, outlier_summary, vita_conditions, window_ratio)


def localisation_markdown(worlds, scenario):
    """The localisation section of suite.md: per mode the distributions, the senses fooled where the
    fusion is not, and each world's instants."""
    what = "kidnap" if scenario == "kidnap" else "session start"
    md = ["", f"## Localisation after each {what}", "",
          "Per mode over every instant: correctly localised (vita-eval: the first re-localisation within the paper's "
          "tolerance after which none is false) within one and two laps of travel, the laps it took (median, 90th "
          "percentile, worst; never: n/a), the false localisations before it, the time spent reporting LOCALISING and "
          "the mean position error of the events after it.", "",
          "| mode | instants | localised | <= 1 lap | <= 2 laps | laps median | 90th pct | worst | never | "
          "without false loc. | false loc. total | most at one | LOCALISING s median | error after median (m) | worst (m) |",
          "|" + "---|" * 15]
    for m in MODES:
        x = localisation_summary(worlds, m)
        md.append(f"| {m} | {x['instants']} | {x['localised']} | {x['within_one_lap']} | {x['within_max_laps']} | "
                  f"{fmt(x['laps']['median'], '.2f')} | {fmt(x['laps']['p10'], '.2f')} | {fmt(x['laps']['worst'], '.2f')} | "
                  f"{x['laps']['undefined']} | {x['without_false_localisation']} | {x['false_localisations_total']} | "
                  f"{fmt(x['false_localisations']['worst'], 'd')} | {fmt(x['localising_s']['median'], '.1f')} | "
                  f"{fmt(x['lem_after_m']['median'], '.3f')} | {fmt(x['lem_after_m']['worst'], '.3f')} |")
    for m in ("visual", "tactile"):
        f = fooled_where_fusion_is_not(worlds, m)
        md += ["", f"{m.capitalize()} alone took a false localisation where ViTa took none after {len(f)} instant(s)"
               + (": " + ", ".join(f"world {wi} at {i['t_s']:.0f} s ({i['false_localisations']})" for wi, i in f[:12])
                  + (", ..." if len(f) > 12 else "") if f else "") + "."]
    md += ["", "| world | seed | instant (s) | " + " | ".join(f"{m} laps | {m} false" for m in MODES) + " |",
           "|" + "---|" * (3 + 2 * len(MODES))]
    for w in worlds:
        loc = w.get("localisation") or {}
        for k, v in enumerate(loc.get("vita") or []):
            cells = [str(w["index"]), str(w["world_seed"]), f"{v['t_s']:.0f}" + (f" (session {v['session']})" if v["session"] else "")]
            for m in MODES:
                i = (loc.get(m) or [None] * (k + 1))[k]
                cells += ["never" if not i["localised"] else fmt(i["laps"], ".2f"), str(i["false_localisations"])]
            md.append("| " + " | ".join(cells) + " |")
    return md


def outliers_markdown(worlds, summary):
    """The outlier section of suite.md: per kind and mode the ATE ratio to the clean run and the wrong
    links kept; each world's ratios."""
    md = ["", "## Wrong closures injected", "",
          "Each world's run replayed with one wrong closure added for every closure the SLAM made (slamd "
          "--inject-wrong-closures; random: far away; group: 5 consecutive cycles onto an earlier pass elsewhere). "
          "ATE ratio: the injected run's over the clean run's (median, 90th percentile, worst); wrong links kept: "
          "links of the final map off by more than the false-closure tolerance against the truth and not revoked.", "",
          "| kind | mode | ATE ratio median | 90th pct | worst | wrong links kept median | worst | worlds keeping one |",
          "|---|---|---|---|---|---|---|---|"]
    for kind in WRONG_CLOSURE_KINDS:
        for m in MODES:
            x = summary[kind][m]
            md.append(f"| {kind} | {m} | {fmt(x['ate_ratio']['median'], '.3f')} | {fmt(x['ate_ratio']['p10'], '.3f')} | "
                      f"{fmt(x['ate_ratio']['worst'], '.3f')} | {fmt(x['wrong_links_kept']['median'], '.1f')} | "
                      f"{fmt(x['wrong_links_kept']['worst'], '.0f')} | {x['worlds_keeping_a_wrong_link']} |")
    md += ["", "| world | seed | ViTa ATE clean (m) | " + " | ".join(f"{k} ratio" for k in WRONG_CLOSURE_KINDS) + " |",
           "|" + "---|" * (3 + len(WRONG_CLOSURE_KINDS))]
    for w in worlds:
        md.append(f"| {w['index']} | {w['world_seed']} | {fmt(w['modes']['vita']['ate'], '.3f')} | "
                  + " | ".join(fmt(outlier_ratio(w, k), ".3f") for k in WRONG_CLOSURE_KINDS) + " |")
    return md


def long_markdown(worlds, summary):
    """The long-run section of suite.md: per mode the last window's ATE over the first's and each
    window's ATE (median, 90th percentile, worst); each world's windows for ViTa and vision."""
    md = ["", "## ATE per window of laps", "",
          "ATE (position RMSE, m) in each window of 4 laps under the run's best-fit alignment; last/first: the last "
          "window's over the first's (median, 90th percentile, worst).", "",
          "| mode | last/first median | 90th pct | worst | " + " | ".join(
              f"window {k + 1} median / worst" for k in range(len(summary["vita"]["windows"]))) + " |",
          "|" + "---|" * (4 + len(summary["vita"]["windows"]))]
    for m in MODES:
        x = summary[m]
        md.append(f"| {m} | {fmt(x['last_over_first']['median'], '.2f')} | {fmt(x['last_over_first']['p10'], '.2f')} | "
                  f"{fmt(x['last_over_first']['worst'], '.2f')} | " + " | ".join(
                      f"{fmt(d['median'], '.3f')} / {fmt(d['worst'], '.3f')}" for d in x["windows"]) + " |")
    md += ["", "| world | seed | ViTa last/first | ViTa ATE | vision ATE | ViTa windows (m) |", "|---|---|---|---|---|---|"]
    for w in worlds:
        v = w["modes"]["vita"]
        md.append(f"| {w['index']} | {w['world_seed']} | {fmt(window_ratio(w), '.2f')} | {fmt(v['ate'], '.3f')} | "
                  f"{fmt(w['modes']['visual']['ate'], '.3f')} | "
                  + " ".join(fmt(x, ".3f") for x in (v.get("ate_windows") or [])) + " |")
    return md


def ran_as(a):
    if a.slurm_array:
        return f"as Slurm array job {a.slurm_array}"
    return f"with {a.jobs} jobs" if a.jobs else "on Slurm"


def half_step_beyond(v, thresholds):
    """Where half the ViTa run's median experience step exceeds the paper's thresholds (then the
    nearest experience can be further than them: a neighbour miss is unavoidable)."""
    if not thresholds or v.get("spacing_m") is None or v.get("spacing_deg") is None:
        return "n/a"
    out = [unit for unit, half, limit in (("m", v["spacing_m"] / 2, thresholds["correct_m"]),
                                          ("deg", v["spacing_deg"] / 2, thresholds["correct_deg"])) if half > limit]
    return " and ".join(out) if out else "no"


def aggregate(a, records, failed, wall_s):
    """suite.json, suite.md and the plots from the worlds' records: the one summary of both executors."""
    worlds = sorted(records, key=lambda w: w["index"])
    summary = {m: {k: distribution([w["modes"][m][k] for w in worlds], b) for k, _, b in METRICS} for m in MODES}
    for m in MODES:
        summary[m]["false_closures"]["worlds_with_any"] = sum(1 for w in worlds if (w["modes"][m]["false_closures"] or 0) > 0)
    if a.scenario == "normal":
        targets = check_targets(worlds, a.family, a.faults)
    elif a.scenario == "long":
        targets = check_long_targets(worlds) if a.family == "aliased" and worlds else []
        summary["long"] = {m: long_summary(worlds, m) for m in MODES}
    elif a.scenario == "outliers":
        targets = check_outlier_targets(worlds, WRONG_CLOSURE_KINDS) if a.family == "aliased" and worlds else []
        summary["outliers"] = {k: {m: outlier_summary(worlds, k, m) for m in MODES} for k in WRONG_CLOSURE_KINDS}
    else:
        targets = check_localisation_targets(worlds, a.scenario) if a.family == "aliased" else []
        summary["localisation"] = {m: localisation_summary(worlds, m) for m in MODES}
    # A world that failed, or has no result of this run (not run; run with other options or programs),
    # is a miss like n/a: the targets over the others would otherwise read "met" for the whole suite.
    have = {w["index"] for w in worlds} | {f["index"] for f in failed}
    missing = [i for i in range(1, a.worlds + 1) if i not in have]
    if targets and (failed or missing):
        seeds = lambda ids: [f"world {i} (seed {world_seed(a.suite_seed, i)})" for i in ids]  # noqa: E731
        targets.insert(0, {"target": f"every one of the {a.worlds} worlds run and evaluated",
                           "measured": f"{len(worlds)} of {a.worlds}: {len(failed)} failed, {len(missing)} without a "
                                       "result of this run",
                           "met": False, "worlds_missed": seeds(sorted([f["index"] for f in failed] + missing))})
    checked = bool(targets)
    misses = miss_lines(targets)
    per_world_ok = {w["index"]: all(vita_conditions(w).values()) if a.family == "aliased" else None for w in worlds}
    fooled_counts = {m: sum(1 for w in worlds if fooled(w, m)) for m in ("visual", "tactile")}
    thresholds = next((w["thresholds"] for w in worlds if w.get("thresholds")), None)
    doc = {
        "suite_seed": a.suite_seed, "family": a.family, "faults": a.faults, "worlds_requested": a.worlds,
        "laps_override": a.laps, "config": os.path.relpath(a.config, ROOT) if a.config.startswith(ROOT) else a.config,
        "config_sha256": file_digest(a.config), "wall_time_s": round(wall_s, 1), "jobs": a.jobs,
        "scenario": a.scenario, "executor": a.executor, "slurm": {"array_job": a.slurm_array, "aggregate_job": os.environ.get("SLURM_JOB_ID")}
        if a.slurm_array else None,
        "thresholds": thresholds, "summary": summary, "fooled": fooled_counts, "targets_checked": checked,
        "targets": targets, "target_misses": misses, "failed_worlds": failed, "missing_worlds": missing,
        "worlds": worlds,
    }
    write_json(os.path.join(a.results, "suite.json"), doc)
    plots = [] if a.no_plots or not worlds else write_plots(worlds, a, per_world_ok)

    md = [f"# World suite: family `{a.family}`{' with sensor faults' if a.faults else ''}"
          f"{'' if a.scenario == 'normal' else f', scenario {a.scenario}'}, suite seed {a.suite_seed}", ""]
    md.append(f"{len(worlds)} worlds ({len(failed)} failed){f', {a.laps} laps each' if a.laps else ''}; "
              f"parameters `{doc['config']}` (sha256 {doc['config_sha256']}); {wall_s:.0f} s {ran_as(a)}. "
              f"Rerun: `scripts/suite --worlds {a.worlds} --suite-seed {a.suite_seed} --family {a.family}"
              f"{' --faults' if a.faults else ''}{'' if a.scenario == 'normal' else f' --scenario {a.scenario}'}"
              f"{' --quick' if a.quick else ''}{f' --laps {a.laps}' if a.laps else ''}`.")
    md += ["", "## Distributions", "",
           "Per mode and metric: the median, the 10th percentile on the bad side (the 10th for ARR and ARCR, "
           "the 90th for ATE, LEM, EnM and false closures) and the worst world; `n/a` runs (e.g. ARR of a one-lap run) "
           "are left out and counted.", "",
           "| mode | metric | median | 10th pct (bad side) | worst | n/a |", "|---|---|---|---|---|---|"]
    for m in MODES:
        for key, label, _ in METRICS:
            s = summary[m][key]
            spec = {"enm": ".3e", "false_closures": ".1f"}.get(key, ".4f")
            md.append(f"| {m} | {label} | {fmt(s['median'], spec)} | {fmt(s['p10'], spec)} | {fmt(s['worst'], spec)} | {s['undefined']} |")
    if thresholds:
        md += ["", f"A *false closure* is a re-localisation to an experience made more than {thresholds['false_closure_m']:g} m "
               f"or {thresholds['false_closure_deg']:g}° from where the robot truly is; a paper-wrong one (beyond "
               f"{thresholds['correct_m']:g} m / {thresholds['correct_deg']:g}°) within that is a *neighbour miss*."]
    shares = [w["modes"]["vita"]["neighbour_miss_share"] for w in worlds if w["modes"]["vita"].get("neighbour_miss_share") is not None]
    md += ["", "Worlds with any false closure: " + ", ".join(
        f"{m} {summary[m]['false_closures']['worlds_with_any']}" for m in MODES) + f" of {len(worlds)}. "
        f"ViTa's paper-wrong re-localisations that are neighbour misses: median share {fmt(percentile(shares, 50) if shares else None, '.3f')} "
        f"over the {len(shares)} worlds that have any."]
    steps = [w for w in worlds if w["modes"]["vita"].get("spacing_m") is not None]
    if steps:
        beyond = sum(1 for w in steps if half_step_beyond(w["modes"]["vita"], w.get("thresholds")) not in ("no", "n/a"))
        md += ["", f"ViTa's experience spacing (median step to each new experience, by ground truth): median over worlds "
               f"{percentile([w['modes']['vita']['spacing_m'] for w in steps], 50):.3f} m and "
               f"{percentile([w['modes']['vita']['spacing_deg'] for w in steps], 50):.2f}°; half a step exceeds the paper's "
               f"thresholds on {beyond} of {len(steps)} worlds."]
    md += ["", f"Single senses *fooled* (ARCR < {FOOLED_ARCR} with an EnM ≥ {FOOLED_ENM_RATIO:g}× ViTa's): "
           f"vision on {fooled_counts['visual']} of {len(worlds)} worlds, touch on {fooled_counts['tactile']}.", ""]
    if a.scenario == "outliers" and worlds:
        md += outliers_markdown(worlds, summary["outliers"]) + [""]
    elif a.scenario == "long" and worlds:
        md += long_markdown(worlds, summary["long"]) + [""]
    elif a.scenario != "normal" and worlds:
        md += localisation_markdown(worlds, a.scenario) + [""]
    if not worlds:
        md += ["No world finished: no distribution and no target check.", ""]
    elif checked:
        issue = {"normal": "robust-SLAM issue", "outliers": "back-end issue", "long": "back-end issue"}.get(
            a.scenario, "global-localisation issue")
        md += [f"## Targets ({issue})", "", "| target | measured | |", "|---|---|---|"]
        md += [f"| {t['target']} | {t['measured']} | {'met' if t['met'] else '**MISSED**'} |" for t in targets]
        md += ["", "Every target met." if not misses else "Missed:"] + [f"- {x}" for x in misses] + [""]
    else:
        md += [f"No targets are set on the `{a.family}` family: reported only.", ""]
    md += ["## Worlds", "",
           "Worlds where ViTa made a false closure first (most first), then by index. FC: false closures. "
           "ViTa spacing: its median experience step (m, °); '½ step beyond' names where half of it exceeds the paper's "
           "thresholds.", "",
           "| world | seed | side (m) | r (m) | v (m/s) | laps | dir | tactile | "
           + " | ".join(f"{m} ARR | {m} ARCR | {m} ATE | {m} EnM | {m} FC" for m in MODES)
           + " | ViTa spacing (m) | ViTa step (°) | ½ step beyond | ViTa ok |",
           "|" + "---|" * (12 + 5 * len(MODES))]
    def listing(w):
        fc = w["modes"]["vita"]["false_closures"] or 0
        return (fc == 0, -fc, w["index"])
    for w in sorted(worlds, key=listing):
        g = w["generation"]
        cells = [str(w["index"]), str(w["world_seed"]), fmt(g.get("arena_side"), ".2f"), fmt(g.get("trajectory.radius"), ".3f"),
                 fmt(g.get("trajectory.speed"), ".4f"), str(a.laps or int(g.get("trajectory.laps", 0))),
                 str(g.get("trajectory.direction", "")), str(g.get("tactile_landmarks", ""))]
        for m in MODES:
            r = w["modes"][m]
            cells += [fmt(r["arr"], ".3f"), fmt(r["arcr"], ".3f"), fmt(r["ate"], ".3f"), fmt(r["enm"], ".2e"),
                      fmt(r["false_closures"], "d")]
        v = w["modes"]["vita"]
        cells += [fmt(v.get("spacing_m"), ".3f"), fmt(v.get("spacing_deg"), ".2f"), half_step_beyond(v, w.get("thresholds"))]
        ok = per_world_ok[w["index"]]
        cells.append("—" if ok is None else ("yes" if ok else "**no**"))
        md.append("| " + " | ".join(cells) + " |")
    # The worst worlds, each with the command that reruns it alone.
    md += ["", "## Worst worlds (ViTa)", ""]
    def badness(w):
        v = w["modes"]["vita"]
        return (v["false_closures"] or 0, -(v["arcr"] if v["arcr"] is not None else 1.0),
                v["ate"] if v["ate"] is not None else 0.0)
    for w in sorted(worlds, key=badness, reverse=True)[:3]:
        v = w["modes"]["vita"]
        worst = v.get("false_closure_worst_m")
        md.append(f"- world {w['index']} (seed {w['world_seed']}): {fmt(v['false_closures'], 'd')} false closures"
                  + (f" (worst {worst:.2f} m)" if worst is not None else "") + f", ARCR {fmt(v['arcr'], '.3f')}, "
                  f"ATE {fmt(v['ate'], '.3f')} m (the paper's LEM {fmt(v['lem'], '.3f')} m), ARR {fmt(v['arr'], '.3f')}, "
                  f"EnM {fmt(v['enm'], '.5f')}. "
                  f"Rerun alone: `{w['rerun']}`")
    if failed:
        md += ["", "## Failed worlds", ""] + [f"- world {x['index']} (seed {x['world_seed']}): {x['failed']}" for x in failed]
    if plots:
        md += ["", "## Plots", ""] + [f"![{os.path.basename(p)}](plots/{os.path.basename(p)})" for p in plots]
    with open(os.path.join(a.results, "suite.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    return doc


class Progress:
    def __init__(self, total, tty):
        self.total, self.tty, self.done, self.start = total, tty, 0, time.monotonic()
        self.lock = threading.Lock()

    def world(self, rec):
        with self.lock:
            self.done += 1
            el = time.monotonic() - self.start
            eta = el / self.done * (self.total - self.done)
            if "failed" in rec:
                what = f"FAILED: {rec['failed']}"
            else:
                v = rec["modes"]["vita"]
                what = ("resumed" if rec.get("resumed") else "done") + \
                    f": ViTa ARR {fmt(v['arr'], '.3f')} ARCR {fmt(v['arcr'], '.3f')} ATE {fmt(v['ate'], '.3f')}" \
                    f" false closures {fmt(v.get('false_closures'), 'd')}"
                loc = (rec.get("localisation") or {}).get("vita")
                if loc:
                    what += (f"; localised {sum(1 for i in loc if i['localised'])}/{len(loc)}, "
                             f"false localisations {sum(i['false_localisations'] for i in loc)}")
            config = f" [{rec['config']}]" if rec.get("config") else ""
            line = f"[{self.done}/{self.total}] world {rec['index']}{config} (seed {rec['world_seed']}) {what}; ETA {eta:.0f} s"
            if self.tty:
                sys.stderr.write("\r\033[K" + line)
                if self.done == self.total:
                    sys.stderr.write("\n")
            else:
                sys.stderr.write(line + "\n")
            sys.stderr.flush()


def report(a, doc, bins):
    """The summary and the failed worlds on the terminal; the exit status of the suite."""
    name = "study" if a.study else "suite"
    print(open(os.path.join(a.results, name + ".md")).read().split("## Worlds")[0].rstrip())
    print(f"\nsuite: {a.results}/{name}.md, {name}.json, plots/" + (", by-config/" if a.study else ""), file=sys.stderr)
    failed = doc["failed_worlds"]
    if failed:
        print(f"suite: {len(failed)} world(s) failed: " + ", ".join(
            f"{x['index']}{' [' + x['config'] + ']' if x.get('config') else ''} ({x['log']})" for x in failed),
            file=sys.stderr)
        print("suite: rerun only those: " + shlex.join([SCRIPT, *world_options(a, bins), *executor_options(a),
                                                        "--retry-failed"]), file=sys.stderr)
        return 1  # the suite did not run through
    missing = doc.get("missing_worlds") or []
    if missing:
        print(f"suite: {len(missing)} world(s) have no result of this run (not run, or run with other options "
              f"or programs): {', '.join(map(str, missing))}; run the suite again without --retry-failed "
              "(or --aggregate-only after they ran)", file=sys.stderr)
        return 1  # the summary covers only part of the suite
    if a.check and doc["target_misses"]:
        return 1
    return 0
