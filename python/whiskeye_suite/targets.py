"""The targets --check applies (the robust-SLAM targets over a normal suite, restated in ATE with ARR
judged against vision alone; the global-localisation targets over kidnaps and session starts) and the
per-world judgements behind them."""
from .common import fmt
from .stats import distribution, percentile

# The robust-SLAM targets for ViTa over a suite of the aliased family (docs/evaluation.md,
# "Targets"). What a false closure is (its tolerance) is vita-eval's, read from its JSON.
NO_FALSE_CLOSURE_SHARE = (23, 24)  # worlds without a false closure: at least 23 in 24 ...
NO_FALSE_CLOSURE_SHARE_FAULTS = (22, 24)  # ... 22 in 24 with --faults
MAX_FALSE_CLOSURES = 2  # on any world
# Accuracy is ATE (position RMSE after the best-fit SE(2) alignment; docs/evaluation.md).
ATE_GOOD_M, ATE_GOOD_SHARE, ATE_FLOOR_M = 0.10, 0.90, 0.20
ATE_OVER_BEST_SENSE_M = 0.03  # ViTa's ATE at most the better single sense's plus this
ARCR_MEDIAN = 0.98
# ARR is judged against vision alone only (its ceiling depends on the world's path): ViTa's median
# at least vision's, and on every world at most this far below vision's.
ARR_BELOW_VISION = 0.05
FOOLED_ARCR = 0.95  # a single sense closing wrong loops (ARCR below this) ...
FOOLED_ENM_RATIO = 10.0  # ... with an EnM at least this many times ViTa's is "fooled"
# The global-localisation issue's targets for ViTa after kidnaps and session starts (docs/evaluation.md).
LOCALISED_ONE_LAP_SHARE = 0.95  # correctly localised within one lap after at least this share ...
LOCALISED_MAX_LAPS = 2.0  # ... and within this many after every one
NO_FALSE_LOCALISATION_SHARE = 0.95  # no false localisation after at least this share ...
MAX_FALSE_LOCALISATIONS = 1  # ... and at most this many after any
LEM_AFTER_LOCALISATION_M = 0.10  # the mean position error from the localisation on
# The back-end issue's outlier targets for ViTa (docs/evaluation.md): with a wrong closure injected for
# every closure, ATE within this many times the clean run's on at least this share of worlds ...
OUTLIER_ATE_RATIO, OUTLIER_ATE_SHARE = 1.2, 0.90
OUTLIER_ATE_RATIO_MAX = 2.0  # ... and within this on every world
# The back-end issue's long-run targets for ViTa: the last window's ATE (4 laps) at most this many
# times the first window's on at least this share of worlds, and the whole run's ATE at most vision
# alone's plus this on every world.
LONG_LAST_OVER_FIRST, LONG_SHARE = 1.2, 0.90
LONG_OVER_VISION_M = 0.01


def targets_help():
    """The --check targets in words, from the constants that check them."""
    return (f"Targets: no false closure on >= {NO_FALSE_CLOSURE_SHARE[0]}/{NO_FALSE_CLOSURE_SHARE[1]} of worlds "
            f"({NO_FALSE_CLOSURE_SHARE_FAULTS[0]}/{NO_FALSE_CLOSURE_SHARE_FAULTS[1]} with --faults) and at most "
            f"{MAX_FALSE_CLOSURES} on any; ATE <= {ATE_GOOD_M:.2f} m on >= {ATE_GOOD_SHARE:.0%} of worlds, "
            f"<= {ATE_FLOOR_M:.2f} m on every one; ARCR median >= {ARCR_MEDIAN}; never worse than its best sense: "
            f"median ARR >= vision's, and on every world ARR >= vision's - {ARR_BELOW_VISION:.2f} (n/a is a miss), "
            f"ATE <= the better single sense's + {ATE_OVER_BEST_SENSE_M:.2f} m and false closures <= the fewer of "
            f"the single senses'.")


def best_sense(w, key):
    """The better single sense's value of `key` on world `w` (the lower; None when neither has one)."""
    vals = [w["modes"][m][key] for m in ("visual", "tactile") if w["modes"][m][key] is not None]
    return min(vals) if vals else None


def vita_conditions(w):
    """Whether ViTa's run on world `w` meets each per-world part of the targets (the shares' parts
    too); n/a is a miss."""
    v = w["modes"]["vita"]
    fc, ate = v["false_closures"], v["ate"]
    best_ate, best_fc = best_sense(w, "ate"), best_sense(w, "false_closures")
    vision_arr = w["modes"]["visual"]["arr"]
    return {
        "no_false_closure": fc == 0,
        "false_closures_max": fc is not None and fc <= MAX_FALSE_CLOSURES,
        "ate_good": ate is not None and ate <= ATE_GOOD_M,
        "ate_floor": ate is not None and ate <= ATE_FLOOR_M,
        # Where vision has no ARR there is nothing to compare with; ViTa without one where it has is a miss.
        # Rounded: 0.85 against 0.90 is 0.05 below, not 0.05000000000000004.
        "arr_vs_vision": vision_arr is None or (v["arr"] is not None
                                                and round(v["arr"] - vision_arr, 9) >= -ARR_BELOW_VISION),
        "ate_vs_senses": ate is not None and (best_ate is None or ate <= best_ate + ATE_OVER_BEST_SENSE_M),
        "false_closures_vs_senses": fc is not None and (best_fc is None or fc <= best_fc),
    }


def world_name(w):
    return f"world {w['index']} (seed {w['world_seed']})"


def worst_world(worlds, value, worse="high"):
    """The world whose value(w) is worst (None: n/a, the worst of all; `worse` says which way)."""
    sign = 1 if worse == "high" else -1
    return max(worlds, key=lambda w: (value(w) is None, sign * (value(w) or 0)))


def share_target(target, worlds, ok, num, den):
    """A target met when ok(w) holds on at least num/den of the worlds: the count, the need and the
    worlds missed."""
    n, k = len(worlds), sum(1 for w in worlds if ok(w))
    return {"target": target, "measured": f"{k} of {n} worlds (need {-(-num * n // den)})", "met": k * den >= num * n,
            "worlds_missed": [world_name(w) for w in worlds if not ok(w)]}


def every_target(target, worlds, ok, value, show, worse="high"):
    """A target met when ok(w) holds on every world; the worst world's value(w) is shown by show()."""
    missed = [w for w in worlds if not ok(w)]
    worst = worst_world(missed or worlds, value, worse)
    shown = f"worst {show(value(worst))} on {world_name(worst)}"
    return {"target": target, "measured": shown if not missed else f"missed on {len(missed)} of {len(worlds)} worlds; {shown}",
            "met": not missed, "worlds_missed": [world_name(w) for w in missed]}


def check_targets(worlds, family, faults):
    """The robust-SLAM issue's targets over the suite (none are set on `stress`): a list of
    {target, measured, met, worlds_missed}, every target with its measured figure."""
    if family != "aliased" or not worlds:
        return []
    n = len(worlds)
    cond = {w["index"]: vita_conditions(w) for w in worlds}
    vita = lambda w, key: w["modes"]["vita"][key]  # noqa: E731
    name = world_name
    targets = []

    def add(target, measured, met, missed=()):
        targets.append({"target": target, "measured": measured, "met": bool(met), "worlds_missed": list(missed)})

    def share(condition, num, den, target):
        targets.append(share_target(target, worlds, lambda w: cond[w["index"]][condition], num, den))

    def every(condition, target, value, worse="high", spec=".3f"):
        """`value(w)`: the world's number behind the condition (None: n/a, the worst); the worst
        world's is shown, `worse` saying which way is worse."""
        targets.append(every_target(target, worlds, lambda w: cond[w["index"]][condition], value,
                                    lambda v: fmt(v, spec), worse))

    def median(key, mode, floor, target):
        vals = [w["modes"][mode][key] for w in worlds if w["modes"][mode][key] is not None]
        undefined = n - len(vals)
        med = percentile(vals, 50) if vals else None
        measured = f"median {fmt(med, '.3f')}" + (f", n/a on {undefined} of {n} worlds" if undefined else "")
        add(target, measured, med is not None and med >= floor and not undefined,
            [name(w) for w in worlds if w["modes"][mode][key] is None])
        return med

    num, den = NO_FALSE_CLOSURE_SHARE_FAULTS if faults else NO_FALSE_CLOSURE_SHARE
    share("no_false_closure", num, den, f"ViTa: no false closure on >= {num}/{den} of worlds")
    every("false_closures_max", f"ViTa: at most {MAX_FALSE_CLOSURES} false closures on any world",
          lambda w: vita(w, "false_closures"), spec="d")
    share("ate_good", round(ATE_GOOD_SHARE * 100), 100,
          f"ViTa ATE <= {ATE_GOOD_M:.2f} m on >= {ATE_GOOD_SHARE:.0%} of worlds")
    every("ate_floor", f"ViTa ATE <= {ATE_FLOOR_M:.2f} m on every world", lambda w: vita(w, "ate"))
    median("arcr", "vita", ARCR_MEDIAN, f"ViTa ARCR median >= {ARCR_MEDIAN}")
    # Never worse than its best sense. The medians over the same worlds: each over its own defined
    # values compared two different sets of worlds. Where vision has no ARR, ViTa's is not compared;
    # ViTa without one where vision has one is a miss (n/a is the worst).
    seen = [w for w in worlds if w["modes"]["visual"]["arr"] is not None]
    paired = [w for w in seen if w["modes"]["vita"]["arr"] is not None]
    vita_na = len(seen) - len(paired)
    mv, ms = (percentile([w["modes"][m]["arr"] for w in paired], 50) if paired else None for m in ("vita", "visual"))
    add("ViTa median ARR >= vision's median ARR (over the worlds where both have one)",
        f"{fmt(mv, '.3f')} against {fmt(ms, '.3f')} over {len(paired)} worlds"
        + (f"; ViTa n/a on {vita_na}" if vita_na else ""),
        not vita_na and (ms is None or mv >= ms))
    every("arr_vs_vision", f"ViTa ARR >= vision's - {ARR_BELOW_VISION:.2f} on every world "
          "(shown: ViTa's minus vision's)",
          lambda w: None if vita(w, "arr") is None or w["modes"]["visual"]["arr"] is None
          else vita(w, "arr") - w["modes"]["visual"]["arr"], "low", spec="+.3f")
    every("ate_vs_senses", f"ViTa ATE <= min(vision's, touch's) + {ATE_OVER_BEST_SENSE_M:.2f} m on every world "
          "(shown: ViTa's minus the best sense's)",
          lambda w: None if vita(w, "ate") is None or best_sense(w, "ate") is None else vita(w, "ate") - best_sense(w, "ate"),
          spec="+.3f")
    every("false_closures_vs_senses", "ViTa false closures <= min(vision's, touch's) on every world "
          "(shown: ViTa's minus the best sense's)",
          lambda w: None if vita(w, "false_closures") is None or best_sense(w, "false_closures") is None
          else vita(w, "false_closures") - best_sense(w, "false_closures"), spec="+d")
    return targets


def instants(worlds, mode):
    """Every localisation instant of `mode` over the worlds, each with its world's index."""
    return [dict(i, world=w["index"], world_seed=w["world_seed"]) for w in worlds
            for i in ((w.get("localisation") or {}).get(mode) or [])]


def localisation_summary(worlds, mode):
    """Distributions over `mode`'s instants: laps to the first correct localisation (never: n/a),
    false localisations before it, time LOCALISING, the error after it."""
    ins = instants(worlds, mode)
    n = len(ins)
    laps = [i["laps"] if i["localised"] else None for i in ins]
    return {
        "instants": n,
        "localised": sum(1 for i in ins if i["localised"]),
        "within_one_lap": sum(1 for x in laps if x is not None and x <= 1.0),
        "within_max_laps": sum(1 for x in laps if x is not None and x <= LOCALISED_MAX_LAPS),
        "laps": distribution(laps, "low"),
        "false_localisations": distribution([i["false_localisations"] for i in ins], "low"),
        "false_localisations_total": sum(i["false_localisations"] for i in ins),
        "without_false_localisation": sum(1 for i in ins if i["false_localisations"] == 0),
        "localising_s": distribution([i["localising_s"] for i in ins], "low"),
        "lem_after_m": distribution([i["lem_after_m"] for i in ins], "low"),
    }


def fooled_where_fusion_is_not(worlds, mode):
    """Instants where `mode` took a false localisation and ViTa none (the same kidnap or session)."""
    out = []
    for w in worlds:
        loc = w.get("localisation") or {}
        for s, v in zip(loc.get(mode) or [], loc.get("vita") or []):
            if s["false_localisations"] > 0 and v["false_localisations"] == 0:
                out.append((w["index"], s))
    return out


def check_localisation_targets(worlds, scenario):
    """The global-localisation issue's targets for ViTa after every kidnap or session start: a list
    of {target, measured, met, worlds_missed} as check_targets()."""
    ins = instants(worlds, "vita")
    if not ins:
        return []
    n = len(ins)
    what = "kidnaps" if scenario == "kidnap" else "session starts"
    name = lambda i: f"world {i['world']} (seed {i['world_seed']}) at {i['t_s']:.0f} s"  # noqa: E731
    targets = []

    def add(target, measured, met, missed):
        targets.append({"target": target, "measured": measured, "met": bool(met), "worlds_missed": [name(i) for i in missed]})

    one = [i for i in ins if not (i["localised"] and i["laps"] is not None and i["laps"] <= 1.0)]
    k = n - len(one)
    add(f"ViTa: correctly localised within one lap after >= {LOCALISED_ONE_LAP_SHARE:.0%} of {what}",
        f"{k} of {n}", k >= LOCALISED_ONE_LAP_SHARE * n, one)
    late = [i for i in ins if not (i["localised"] and i["laps"] is not None and i["laps"] <= LOCALISED_MAX_LAPS)]
    worst = max((i["laps"] for i in ins if i["localised"] and i["laps"] is not None), default=None)
    add(f"ViTa: correctly localised within {LOCALISED_MAX_LAPS:g} laps after every one of them",
        f"{len(late)} of {n} not" + (f"; slowest {worst:.2f} laps" if worst is not None else ""), not late, late)
    falses = [i for i in ins if i["false_localisations"] > 0]
    add(f"ViTa: no false localisation after >= {NO_FALSE_LOCALISATION_SHARE:.0%} of {what}",
        f"{n - len(falses)} of {n}", n - len(falses) >= NO_FALSE_LOCALISATION_SHARE * n, falses)
    many = [i for i in ins if i["false_localisations"] > MAX_FALSE_LOCALISATIONS]
    add(f"ViTa: at most {MAX_FALSE_LOCALISATIONS} false localisation after any",
        f"most {max(i['false_localisations'] for i in ins)}", not many, many)
    bad = [i for i in ins if i["localised"] and (i["lem_after_m"] is None or i["lem_after_m"] > LEM_AFTER_LOCALISATION_M)]
    worst_lem = max((i["lem_after_m"] for i in ins if i["lem_after_m"] is not None), default=None)
    add(f"ViTa: error after the localisation <= {LEM_AFTER_LOCALISATION_M:.2f} m (mean position error of its events)",
        f"worst {fmt(worst_lem, '.3f')} m", not bad, bad)
    return targets


def times(v):
    """A ratio as '1.23x' (n/a: 'n/a')."""
    return "n/a" if v is None else f"{v:.2f}x"


def outlier_ratio(w, kind, mode="vita"):
    """`mode`'s ATE with wrong closures of `kind` injected over its clean run's on world `w` (None: n/a)."""
    clean = w["modes"][mode]["ate"]
    injected = (((w.get("outliers") or {}).get(kind) or {}).get(mode) or {}).get("ate")
    return None if clean is None or injected is None or clean <= 0 else injected / clean


def outlier_summary(worlds, kind, mode):
    """Over the worlds: the ATE ratio to the clean run, and the wrong links the map kept."""
    kept = [(((w.get("outliers") or {}).get(kind) or {}).get(mode) or {}).get("links_wrong_kept") for w in worlds]
    return {"ate_ratio": distribution([outlier_ratio(w, kind, mode) for w in worlds], "low"),
            "wrong_links_kept": distribution(kept, "low"),
            "worlds_keeping_a_wrong_link": sum(1 for k in kept if k)}


def check_outlier_targets(worlds, kinds):
    """The back-end issue's outlier targets for ViTa, per kind of injected closure: a list of
    {target, measured, met, worlds_missed} as check_targets(); n/a is a miss."""
    targets = []
    for kind in kinds:
        ratios = {w["index"]: outlier_ratio(w, kind) for w in worlds}
        ratio = lambda w: ratios[w["index"]]  # noqa: E731
        targets.append(share_target(f"ViTa with {kind} wrong closures: ATE <= {OUTLIER_ATE_RATIO:g}x the clean run's on "
                                    f">= {OUTLIER_ATE_SHARE:.0%} of worlds", worlds,
                                    lambda w: ratio(w) is not None and ratio(w) <= OUTLIER_ATE_RATIO,
                                    round(OUTLIER_ATE_SHARE * 100), 100))
        targets.append(every_target(f"ViTa with {kind} wrong closures: ATE <= {OUTLIER_ATE_RATIO_MAX:g}x the clean run's "
                                    "on every world", worlds,
                                    lambda w: ratio(w) is not None and ratio(w) <= OUTLIER_ATE_RATIO_MAX, ratio, times))
    return targets


def window_ratio(w, mode="vita"):
    """`mode`'s ATE in its last window of laps over its first (None without two windows)."""
    windows = w["modes"][mode].get("ate_windows") or []
    return windows[-1] / windows[0] if len(windows) >= 2 and windows[0] else None


def long_summary(worlds, mode):
    """Over the worlds: the last window's ATE over the first's, and each window's ATE by position."""
    n = max((len(w["modes"][mode].get("ate_windows") or []) for w in worlds), default=0)
    return {"last_over_first": distribution([window_ratio(w, mode) for w in worlds], "low"),
            "windows": [distribution([window_at(w, mode, k) for w in worlds], "low") for k in range(n)]}


def window_at(w, mode, k):
    """`mode`'s ATE in window k of world `w` (None: the run has fewer windows)."""
    windows = w["modes"][mode].get("ate_windows") or []
    return windows[k] if k < len(windows) else None


def check_long_targets(worlds):
    """The back-end issue's long-run targets for ViTa: a list of {target, measured, met, worlds_missed}
    as check_targets(); n/a is a miss."""
    ratios = {w["index"]: window_ratio(w) for w in worlds}
    ratio = lambda w: ratios[w["index"]]  # noqa: E731
    shape = share_target(f"ViTa: the last window's ATE <= {LONG_LAST_OVER_FIRST:g}x the first window's on "
                         f">= {LONG_SHARE:.0%} of worlds", worlds,
                         lambda w: ratio(w) is not None and ratio(w) <= LONG_LAST_OVER_FIRST, round(LONG_SHARE * 100), 100)
    worst = worst_world(worlds, ratio)
    shape["measured"] += f"; worst {times(ratio(worst))} on {world_name(worst)}"
    over = {w["index"]: None if w["modes"]["vita"]["ate"] is None or w["modes"]["visual"]["ate"] is None
            else w["modes"]["vita"]["ate"] - w["modes"]["visual"]["ate"] for w in worlds}
    margin = lambda w: over[w["index"]]  # noqa: E731
    vision = every_target(f"ViTa's whole-run ATE <= vision alone's + {LONG_OVER_VISION_M:.2f} m on every world", worlds,
                          lambda w: margin(w) is not None and margin(w) <= LONG_OVER_VISION_M + 1e-12, margin,
                          lambda v: f"{fmt(v, '+.3f')} m")
    return [shape, vision]


def miss_lines(targets):
    """A line per missed target: its measured figure and the worlds that missed it."""
    out = []
    for t in targets:
        if t["met"]:
            continue
        line = f"{t['target']}: {t['measured']}"
        if t["worlds_missed"]:
            line += " (" + ", ".join(t["worlds_missed"][:6]) + (", ..." if len(t["worlds_missed"]) > 6 else "") + ")"
        out.append(line)
    return out


def fooled(w, mode):
    """A single sense is fooled when it closes wrong loops with a map error >= 10x ViTa's."""
    s, v = w["modes"][mode], w["modes"]["vita"]
    return (s["arcr"] is not None and s["arcr"] < FOOLED_ARCR and s["enm"] is not None and v["enm"] is not None
            and s["enm"] >= FOOLED_ENM_RATIO * v["enm"])
