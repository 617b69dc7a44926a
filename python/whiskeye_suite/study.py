"""Parameter studies: the same worlds, simulated once, replayed under several slamd configs, and one
summary that compares the configs side by side (study.json, study.md, plots/study_*.png); each
config's own suite summary in by-config/<label>/."""
import argparse
import os
import subprocess

from .common import METRICS, MODES, ROOT, fail, file_digest, fmt, write_json
from .pipeline import collect
from .report import aggregate, ran_as
from .stats import distribution

DISAGREEMENTS_SHOWN = 3  # worlds per metric in "where the configs disagree most"
SPEC = {"enm": ".3e", "false_closures": ".1f"}  # how a metric is written; .4f otherwise


def set_key(text, key, value):
    """`text` (a slamd config in block YAML) with the scalar at dotted `key` set to `value`, its
    comment kept; None when the file does not write that key."""
    path, stack, out, found = key.split("."), [], [], False
    for line in text.split("\n"):
        body = line.split("#", 1)[0]
        name, colon, rest = body.strip().partition(":")
        if colon and name and not body.strip().startswith("-"):
            indent = len(line) - len(line.lstrip(" "))
            while stack and stack[-1][0] >= indent:
                stack.pop()
            here = [k for _, k in stack] + [name]
            if here == path and rest.strip():
                start = line.index(":", indent) + 1
                comment = line[len(body):]
                old = line[start:len(body)]
                new = " " + value
                pad = max(1, len(old) - len(new)) if comment else 0
                line = line[:start] + new + (" " * pad + comment if comment else "")
                found = True
            if not rest.strip():
                stack.append((indent, name))
        out.append(line)
    return "\n".join(out) if found else None


def derive_sweep(a, bins):
    """--sweep KEY=V1,V2,...: the base config with KEY at each value, written to DIR/configs/<leaf>=<V>.yaml
    and checked by slamd's own loader (its --print-config equals the base's with --set KEY=V).
    Returns the study's (label, path) pairs."""
    key, values = a.sweep
    with open(a.config) as f:
        base = f.read()
    d = os.path.join(a.results, "configs")
    os.makedirs(d, exist_ok=True)
    out = []
    for v in values:
        text = set_key(base, key, v)
        if text is None:
            fail(f"--sweep: {a.config} does not set {key} (a sweep varies a key the config writes)")
        label = f"{key.rsplit('.', 1)[1]}={v}"
        path = os.path.join(d, label + ".yaml")
        derived = f"# {os.path.relpath(a.config, ROOT) if a.config.startswith(ROOT) else a.config} with {key}: {v} " \
                  f"(scripts/suite --sweep)\n" + text
        if not os.path.exists(path) or open(path).read() != derived:  # unchanged: its digest, so its worlds, stay
            with open(path, "w") as f:
                f.write(derived)
        if bins:
            slamd = os.path.join(bins, "slamd")
            got = subprocess.run([slamd, "--config", path, "--print-config"], capture_output=True, text=True)
            want = subprocess.run([slamd, "--config", a.config, "--set", f"{key}={v}", "--print-config"],
                                  capture_output=True, text=True)
            if got.returncode != 0 or want.returncode != 0 or got.stdout != want.stdout.replace("  (--set)\n", "\n"):
                err = (want.stderr or got.stderr).strip().splitlines()
                fail(f"--sweep: {key}={v}: " + (err[-1].replace("slamd: ", "") if err else
                                                 f"slamd reads {path} otherwise than --set {key}={v}"))
        out.append((label, path))
    return out


def per_config_options(a, label, config):
    """The options of a one-config suite of `config` whose summary goes to DIR/by-config/<label>/."""
    c = argparse.Namespace(**vars(a))
    c.config, c.results, c.study = config, os.path.join(a.results, "by-config", label), False
    return c


def differences(base, other, better):
    """Per-world `other - base` where both are defined: its spread, and how many worlds got better,
    worse or stayed the same (by the metric's better side)."""
    deltas = [o - b for b, o in zip(base, other) if b is not None and o is not None]
    if not deltas:
        return {"median": None, "min": None, "max": None, "n": 0, "better": 0, "worse": 0, "same": 0}
    sign = 1 if better == "high" else -1
    return {"median": distribution(deltas, "low")["median"], "min": min(deltas), "max": max(deltas), "n": len(deltas),
            "better": sum(1 for x in deltas if sign * x > 0), "worse": sum(1 for x in deltas if sign * x < 0),
            "same": sum(1 for x in deltas if x == 0)}


def compare(labels, by_label, indices):
    """The side-by-side part of study.json from each config's records: distributions, per-world
    differences against the first config, the worlds where the configs disagree most."""
    value = {lab: {w["index"]: w for w in by_label[lab]} for lab in labels}

    def series(lab, mode, key):
        return [value[lab][i]["modes"][mode][key] if i in value[lab] else None for i in indices]

    summary = {lab: {m: {k: distribution(series(lab, m, k), b) for k, _, b in METRICS} for m in MODES} for lab in labels}
    diffs = {lab: {m: {k: differences(series(labels[0], m, k), series(lab, m, k), b) for k, _, b in METRICS}
                   for m in MODES} for lab in labels[1:]}
    disagree = {}
    for m in MODES:
        disagree[m] = {}
        for k, _, _ in METRICS:
            rows = []
            for n, i in enumerate(indices):
                vals = {lab: series(lab, m, k)[n] for lab in labels}
                known = [v for v in vals.values() if v is not None]
                if len(known) >= 2:
                    rows.append({"world": i, "spread": max(known) - min(known), "values": vals})
            rows.sort(key=lambda r: (-r["spread"], r["world"]))
            disagree[m][k] = [r for r in rows if r["spread"] > 0][:DISAGREEMENTS_SHOWN]
    return summary, diffs, disagree


def aggregate_study(a, keys, wall_s):
    """Every config's suite summary (by-config/<label>/) and the comparison (study.json, study.md,
    plots/study_*.png). Returns the study's document; its failed worlds and target misses span the configs."""
    labels = [lab for lab, _ in a.variants]
    by_label, failed, targets, misses = {}, [], {}, []
    for lab, config in a.variants:
        records, fails = collect(a, keys[lab], lab)
        by_label[lab] = sorted(records, key=lambda w: w["index"])
        failed += fails
        c = per_config_options(a, lab, config)
        os.makedirs(c.results, exist_ok=True)
        doc = aggregate(c, records, fails, wall_s)
        targets[lab] = doc["targets"]
        misses += [f"{lab}: {x}" for x in doc["target_misses"]]
    indices = sorted({w["index"] for lab in labels for w in by_label[lab]})
    seeds = {w["index"]: w["world_seed"] for lab in labels for w in by_label[lab]}
    summary, diffs, disagree = compare(labels, by_label, indices)
    rel = lambda p: os.path.relpath(p, ROOT) if p.startswith(ROOT) else p  # noqa: E731
    doc = {
        "study": True, "suite_seed": a.suite_seed, "family": a.family, "faults": a.faults, "scenario": a.scenario,
        "worlds_requested": a.worlds, "laps_override": a.laps, "quick": a.quick,
        "configs": [{"label": lab, "config": rel(path), "config_sha256": file_digest(path),
                     "worlds": len(by_label[lab]), "summary": f"by-config/{lab}/suite.md"} for lab, path in a.variants],
        "baseline": labels[0], "world_config": rel(a.world_config), "world_config_sha256": file_digest(a.world_config),
        "sweep": {"key": a.sweep[0], "values": a.sweep[1]} if a.sweep else None,
        "wall_time_s": round(wall_s, 1), "jobs": a.jobs, "executor": a.executor,
        "slurm": {"array_job": a.slurm_array, "aggregate_job": os.environ.get("SLURM_JOB_ID")} if a.slurm_array else None,
        "summary": summary, "differences": diffs, "disagreements": disagree,
        "targets": {lab: {"checked": bool(t), "met": sum(1 for x in t if x["met"]), "of": len(t),
                          "missed": [x["target"] for x in t if not x["met"]]} for lab, t in targets.items()},
        "target_misses": misses, "failed_worlds": failed,
        "worlds": [{"index": i, "world_seed": seeds[i],
                    "configs": {lab: next((w["modes"] for w in by_label[lab] if w["index"] == i), None) for lab in labels}}
                   for i in indices],
    }
    write_json(os.path.join(a.results, "study.json"), doc)
    plots = [] if a.no_plots or not indices else write_study_plots(a, labels, by_label, indices)
    with open(os.path.join(a.results, "study.md"), "w") as f:
        f.write("\n".join(study_markdown(a, doc, targets, plots)) + "\n")
    return doc


def study_markdown(a, doc, targets, plots):
    """study.md: the configs side by side, the per-world differences, where they disagree most."""
    labels = [c["label"] for c in doc["configs"]]
    base = labels[0]
    n = len(doc["worlds"])
    what = f"`{doc['sweep']['key']}` swept over {', '.join(doc['sweep']['values'])}" if doc["sweep"] else \
        f"{len(labels)} configs"
    md = [f"# Parameter study: {what}; family `{a.family}`{' with sensor faults' if a.faults else ''}"
          f"{'' if a.scenario == 'normal' else f', scenario {a.scenario}'}, suite seed {a.suite_seed}", ""]
    md.append(f"{n} worlds{f', {a.laps} laps each' if a.laps else ''}, each simulated once and replayed under every "
              f"config ({len(doc['failed_worlds'])} failed world-config pairs); the worlds drawn with "
              f"`{doc['world_config']}`; {doc['wall_time_s']:.0f} s {ran_as(a)}. Each config's full suite summary: "
              "`by-config/<config>/suite.md`.")
    md += ["", "| config | file | sha256 | worlds |", "|---|---|---|---|"]
    md += [f"| {c['label']}{' (baseline)' if c['label'] == base else ''} | `{c['config']}` | {c['config_sha256']} | "
           f"{c['worlds']} |" for c in doc["configs"]]
    md += ["", "## Side by side", "",
           "Per mode and metric, each config's median / 10th percentile on the bad side / worst world (the 10th "
           "percentile for ARR and ARCR, the 90th for ATE, LEM, EnM and false closures; `n/a` runs left out).", "",
           "| mode | metric | " + " | ".join(labels) + " |", "|" + "---|" * (2 + len(labels))]
    for m in MODES:
        for key, label, _ in METRICS:
            spec = SPEC.get(key, ".4f")
            cells = []
            for lab in labels:
                s = doc["summary"][lab][m][key]
                cells.append(" / ".join(fmt(s[x], spec) for x in ("median", "p10", "worst"))
                             + (f" ({s['undefined']} n/a)" if s["undefined"] else ""))
            md.append(f"| {m} | {label} | " + " | ".join(cells) + " |")
    if len(labels) > 1:
        md += ["", f"## Per-world differences against {base}", "",
               f"Each world's value under the config minus under {base}, over the worlds where both are defined: "
               "the median, smallest and largest difference, and on how many worlds the config is better, worse or "
               "the same.", "",
               "| config | mode | metric | median Δ | smallest Δ | largest Δ | better | worse | same |",
               "|---|---|---|---|---|---|---|---|---|"]
        for lab in labels[1:]:
            for m in MODES:
                for key, label, _ in METRICS:
                    x = doc["differences"][lab][m][key]
                    spec = "+" + SPEC.get(key, ".4f")
                    md.append(f"| {lab} | {m} | {label} | {fmt(x['median'], spec)} | {fmt(x['min'], spec)} | "
                              f"{fmt(x['max'], spec)} | {x['better']} | {x['worse']} | {x['same']} |")
    md += ["", "## Where the configs disagree most (ViTa)", "",
           f"Per metric, the {DISAGREEMENTS_SHOWN} worlds with the largest spread between the configs (none: the "
           "configs agree on every world)."]
    seeds = {w["index"]: w["world_seed"] for w in doc["worlds"]}
    for key, label, _ in METRICS:
        rows = doc["disagreements"]["vita"][key]
        spec = SPEC.get(key, ".4f")
        md.append(f"- {label}: " + ("; ".join(
            f"world {r['world']} (seed {seeds[r['world']]}): "
            + ", ".join(f"{lab} {fmt(r['values'][lab], spec)}" for lab in labels) for r in rows) if rows else "none") + ".")
    if any(targets.values()):
        names = [t["target"] for t in next(t for t in targets.values() if t)]
        md += ["", "## Targets", "", "| target | " + " | ".join(labels) + " |", "|" + "---|" * (1 + len(labels))]
        for k, name in enumerate(names):
            md.append(f"| {name} | " + " | ".join(
                (("met" if targets[lab][k]["met"] else "**MISSED**") + f" ({targets[lab][k]['measured']})")
                if len(targets[lab]) > k else "—" for lab in labels) + " |")
    md += ["", "## Worlds", "", "ViTa under each config: ARR, ARCR, ATE (m), false closures.", "",
           "| world | seed | " + " | ".join(f"{lab} ARR | {lab} ARCR | {lab} ATE | {lab} FC" for lab in labels) + " |",
           "|" + "---|" * (2 + 4 * len(labels))]
    for w in doc["worlds"]:
        cells = [str(w["index"]), str(w["world_seed"])]
        for lab in labels:
            v = (w["configs"][lab] or {}).get("vita")
            cells += ["—"] * 4 if v is None else [fmt(v["arr"], ".3f"), fmt(v["arcr"], ".3f"), fmt(v["ate"], ".3f"),
                                                   fmt(v["false_closures"], "d")]
        md.append("| " + " | ".join(cells) + " |")
    if doc["failed_worlds"]:
        md += ["", "## Failed", ""] + [f"- world {x['index']} (seed {x['world_seed']}) under {x.get('config')}: "
                                       f"{x['failed']}" for x in doc["failed_worlds"]]
    if plots:
        md += ["", "## Plots", ""] + [f"![{os.path.basename(p)}](plots/{os.path.basename(p)})" for p in plots]
    return md


def write_study_plots(a, labels, by_label, indices):
    """Each metric per mode and config (a world's values joined across the configs), and ViTa's
    per-world differences against the first config."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    d = os.path.join(a.results, "plots")
    os.makedirs(d, exist_ok=True)
    value = {lab: {w["index"]: w["modes"] for w in by_label[lab]} for lab in labels}

    def get(lab, i, m, k):
        return value[lab][i][m][k] if i in value[lab] else None

    x = range(1, len(labels) + 1)
    fig, axes = plt.subplots(len(MODES), len(METRICS), figsize=(3.6 * len(METRICS), 3.0 * len(MODES)), squeeze=False)
    for r, m in enumerate(MODES):
        for c, (k, label, better) in enumerate(METRICS):
            ax = axes[r][c]
            for i in indices:
                ys = [get(lab, i, m, k) for lab in labels]
                pts = [(xi, y) for xi, y in zip(x, ys) if y is not None]
                if pts:
                    ax.plot(*zip(*pts), color="grey", alpha=0.35, linewidth=0.8, marker="o", markersize=3)
            data = [[get(lab, i, m, k) for i in indices if get(lab, i, m, k) is not None] for lab in labels]
            pos = [xi for xi, vals in zip(x, data) if vals]
            if pos:
                ax.boxplot([vals for vals in data if vals], positions=pos, widths=0.4, showfliers=False)
            ax.set_xticks(list(x), labels, rotation=20, fontsize=7)
            ax.set_title(f"{m}: {label} ({'higher' if better == 'high' else 'lower'} is better)", fontsize=8)
            if k == "enm" and all(v > 0 for vals in data for v in vals) and any(data):
                ax.set_yscale("log")
            ax.grid(alpha=0.3)
    fig.suptitle(f"{len(indices)} worlds under {len(labels)} configs (a line joins a world's values)")
    fig.tight_layout()
    written = [os.path.join(d, "study_metrics.png")]
    fig.savefig(written[-1], dpi=100)
    plt.close(fig)
    if len(labels) > 1:
        fig, axes = plt.subplots(1, len(METRICS), figsize=(3.6 * len(METRICS), 3.4), squeeze=False)
        for ax, (k, label, better) in zip(axes[0], METRICS):
            for n, lab in enumerate(labels[1:], start=1):
                ds = [get(lab, i, "vita", k) - get(labels[0], i, "vita", k) for i in indices
                      if get(lab, i, "vita", k) is not None and get(labels[0], i, "vita", k) is not None]
                ax.scatter([n + 0.08 * ((j % 5) - 2) for j in range(len(ds))], ds, s=14)
            ax.axhline(0.0, color="black", linewidth=0.8)
            ax.set_xticks(range(1, len(labels)), labels[1:], rotation=20, fontsize=7)
            ax.set_title(f"ViTa {label}: minus {labels[0]} ({'up' if better == 'high' else 'down'} is better)",
                         fontsize=8)
            ax.grid(alpha=0.3)
        fig.tight_layout()
        written.append(os.path.join(d, "study_differences.png"))
        fig.savefig(written[-1], dpi=100)
        plt.close(fig)
    return written
