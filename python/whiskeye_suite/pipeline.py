"""One world's job, whichever executor runs it: generate, simulate, replay the three modes, evaluate;
its record (world.json) or its failure (failed.json) in the results folder, and reading them back."""
import json
import math
import os
import random
import shutil
import subprocess
import time

from .common import (KIDNAPS_PER_WORLD, MODES, PROGRAMS, RESTART_SESSION_LAPS, RESTART_SESSION_UTIME,
                     RESTART_SESSION_UTIME_STEP, RESTART_SESSIONS, WRONG_CLOSURE_KINDS, file_digest, read_json,
                     world_seed, write_json)
from .records import read_record


class WorldFailed(Exception):
    pass


def run(cmd, log):
    """Runs one step, its output appended to the world's log; raises WorldFailed naming it."""
    with open(log, "a") as out:
        out.write("$ " + " ".join(cmd) + "\n")
        out.flush()
        try:
            r = subprocess.run(cmd, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        except OSError as e:  # a program missing or not executable (being rebuilt): this world fails, not the suite
            out.write(f"{cmd[0]}: {e.strerror}\n")
            raise WorldFailed(f"{os.path.basename(cmd[0])} could not run: {e.strerror} (see {log})") from None
    if r.returncode != 0:
        raise WorldFailed(f"{os.path.basename(cmd[0])} exited {r.returncode} (see {log})")


def generation_of(path):
    """The generator's header lines and drawn parameters from the JSON vita-sim writes beside a
    generated world (--output-world-json): a section's fields as "section.field"."""
    with open(path) as f:
        doc = json.load(f)
    out = {}
    for k, v in doc.items():
        if isinstance(v, dict):
            out.update({f"{k}.{field}": x for field, x in v.items()})
        else:
            out[k] = v
    return out


def metrics_of(run):
    lem = (run.get("lem") or {}).get("position_m")
    ate = run.get("ate") or {}
    exm = run["exm"]
    spacing = exm.get("experience_spacing") or {}
    return {
        "arr": exm["arr"],
        "arcr": exm["arcr"],
        "ate": (ate.get("position_m") or {}).get("rmse"),
        # ATE per window of laps (vita-eval --ate-window-laps), under the run's alignment.
        "ate_windows": [w["rmse_m"] for w in ate.get("windows") or []],
        "lem": lem["rmse"] if lem else None,
        "enm": run["enm"]["enm"],
        "experiences": run["counts"]["map_experiences"],
        # Links of the final map the back end revoked (none from a slamd before it).
        "links_revoked": run["counts"].get("map_links_revoked"),
        # The final map's links against the truth (vita-eval): wrong ones kept bend the map.
        "links_wrong": (run.get("links") or {}).get("wrong"),
        "links_wrong_kept": (run.get("links") or {}).get("wrong_kept"),
        "links_right_revoked": (run.get("links") or {}).get("right_revoked"),
        "relocalisations": exm["relocalisations_total"],
        "false_closures": exm.get("false_closures"),
        "false_closure_worst_m": exm.get("false_closure_worst_m"),
        "neighbour_misses": exm.get("neighbour_misses"),
        "neighbour_miss_share": exm.get("neighbour_miss_share"),
        "spacing_m": spacing.get("median_m"),
        "spacing_deg": spacing.get("median_heading_deg"),
    }


def thresholds_of(params):
    """vita-eval's correct-relocalisation thresholds and false-closure tolerance (m, degrees)."""
    return {"correct_m": params["correct_position_m"], "correct_deg": round(math.degrees(params["correct_angle_rad"]), 9),
            "false_closure_m": params["false_closure_position_m"],
            "false_closure_deg": round(math.degrees(params["false_closure_angle_rad"]), 9)}


def world_dir(a, index):
    return os.path.join(a.results, f"world-{index:03d}")


def variant_dir(a, index, label):
    """Where a world's results under one config go: the world's folder in a one-config suite (label
    None), its subfolder named by the config in a parameter study."""
    return world_dir(a, index) if label is None else os.path.join(world_dir(a, index), label)


def world_key(a, bins, config=None):
    """What makes a world's result: the options, the parameters and the programs (its seed aside).
    In a parameter study also the config the worlds were drawn with."""
    config = config or a.config
    study = {"world_config": file_digest(a.world_config)} if a.study else {}
    return json.dumps({"family": a.family, "faults": a.faults, "scenario": a.scenario, "quick": a.quick, "laps": a.laps,
                       **({"camera_format": a.camera_format} if a.camera_format else {}),
                       "config": file_digest(config), **study,
                       "robot": file_digest(a.robot), "programs": [file_digest(os.path.join(bins, t)) for t in PROGRAMS]},
                      sort_keys=True)


def world_keys(a, bins):
    """Each config's key, by its label (None in a one-config suite)."""
    return {label: world_key(a, bins, config) for label, config in a.variants}


def world_state(a, index, key, label=None):
    """('done', record), ('failed', failure) or ('todo', None) for world `index` under config `label`
    in DIR. A record or failure counts only for this world (the seed) and, given a key, for the same
    options and programs. One that is no such record (records.read_record) raises BadRecord: the
    suite stops naming it rather than resume or summarise from it."""
    seed = world_seed(a.suite_seed, index)
    for state, name in (("done", "world.json"), ("failed", "failed.json")):
        doc = read_record(os.path.join(variant_dir(a, index, label), name), index, "world" if state == "done" else "failed")
        if doc and doc.get("world_seed") == seed and (key is None or doc.get("key") == key):
            return state, doc
    return "todo", None


def record_failure(a, index, key, message, log, label=None, **extra):
    """A world's failure, kept in DIR so that the aggregation lists it and --retry-failed finds it."""
    d = variant_dir(a, index, label)
    os.makedirs(d, exist_ok=True)
    failure = {"index": index, "world_seed": world_seed(a.suite_seed, index), "key": key, "failed": message, "log": log,
               **({"config": label} if label is not None else {}), **extra}
    write_json(os.path.join(d, "failed.json"), failure)
    return failure


def run_world(a, bins, index, keys, scratch):
    """Generate, simulate, then per config replay three modes and evaluate: the job for one world,
    whichever executor runs it. The world is simulated once for every config it has no record for.
    The simulator and replay logs go to `scratch` (deleted here). Writes every config's record
    (world.json) or failure (failed.json) and returns them in the order of a.variants."""
    states = {label: world_state(a, index, keys[label], label) for label, _ in a.variants}
    todo = [(label, config) for label, config in a.variants if states[label][0] != "done"]
    if not todo:
        return [dict(states[label][1], resumed=True) for label, _ in a.variants]
    seed = world_seed(a.suite_seed, index)
    d = world_dir(a, index)
    for label, _ in todo:
        os.makedirs(variant_dir(a, index, label), exist_ok=True)
        record_path = os.path.join(variant_dir(a, index, label), "world.json")
        if os.path.exists(record_path):
            os.remove(record_path)  # another world's or other options': it must not stand in for this run
    log = os.path.join(d, "run.log")
    open(log, "w" if len(todo) == len(a.variants) else "a").close()  # a study's configs already done keep their log
    world = os.path.join(d, "world.yaml")
    generated = os.path.join(d, "generation.json")
    sim_log = os.path.join(scratch, "sim.lcmlog")
    t0 = time.monotonic()
    timings = {}
    done = {}
    try:
        gen = [os.path.join(bins, "vita-sim"), "--generate-world", "--world-seed", str(seed), "--family", a.family,
               "--output-world", world, "--output-world-json", generated, "--robot", a.robot, "--slam-config",
               a.world_config]
        if a.faults:
            gen.append("--faults")
        if a.scenario == "kidnap":
            gen += ["--kidnaps", str(1 if a.quick else KIDNAPS_PER_WORLD)]
        run(gen, log)
        timings["generate_s"] = time.monotonic() - t0
        t = time.monotonic()
        sim = [os.path.join(bins, "vita-sim"), "--world", world, "--robot", a.robot, "--seed", str(seed), "--output",
               sim_log, "--quiet"]
        if a.laps:
            sim += ["--laps", str(a.laps)]
        if a.camera_format:
            sim += ["--camera-format", a.camera_format]
        run(sim, log)
        timings["simulate_s"] = time.monotonic() - t
        for n, (label, config) in enumerate(todo):
            done[label] = replay_and_evaluate(a, bins, index, keys[label], label, config, world, generated, sim_log,
                                              scratch, log, dict(timings), last=n == len(todo) - 1)
    except WorldFailed as e:
        for label, _ in todo:
            if label not in done:
                done[label] = record_failure(a, index, keys[label], str(e), log, label)
    finally:
        if os.path.exists(sim_log):
            os.remove(sim_log)
    return [done[label] if label in done else dict(states[label][1], resumed=True) for label, _ in a.variants]


def replay_and_evaluate(a, bins, index, key, label, config, world, generated, sim_log, scratch, log, timings, last):
    """One config's part of a world: slamd --replay in the three modes, vita-eval, the record. The
    simulator log is removed after the last config's replays (peak disk: one simulator log per job).
    A step that fails is this config's failure (failed.json); the world's other configs still run."""
    seed = world_seed(a.suite_seed, index)
    d = variant_dir(a, index, label)
    outs = [os.path.join(scratch, f"slam-{mode}.lcmlog") for mode in MODES]
    try:
        t = time.monotonic()
        for mode, out in zip(MODES, outs):
            saved = []
            if a.scenario == "restart":  # the map the sessions localise in: slamd's final checkpoint
                shutil.rmtree(os.path.join(scratch, f"state-{mode}"), ignore_errors=True)
                saved = ["--state-dir", os.path.join(scratch, f"state-{mode}"), "--checkpoint-every", "0"]
            run([os.path.join(bins, "slamd"), "--replay", sim_log, "--output", out, "--mode", mode, "--config",
                 config, "--robot", a.robot, *saved], log)
        timings["replay_s"] = time.monotonic() - t
        if last and a.scenario != "outliers":
            os.remove(sim_log)
        t = time.monotonic()
        evaluate = [os.path.join(bins, "vita-eval"), "--json", os.path.join(d, "metrics.json"), "--trace",
                    os.path.join(d, "trace")]
        for out in outs:
            evaluate += ["--input", out]
        if not a.no_plots:
            evaluate += ["--plots", os.path.join(d, "plots"), "--world", world]  # the world under the maps
        run(evaluate, log)
        timings["evaluate_s"] = time.monotonic() - t
        if a.scenario == "outliers":
            t = time.monotonic()
            outliers = run_outliers(a, bins, seed, world, sim_log, outs, d, log, config)
            timings["outliers_s"] = time.monotonic() - t
            if last:
                os.remove(sim_log)
        if a.scenario == "restart":
            t = time.monotonic()
            sessions = run_sessions(a, bins, seed, world, scratch, outs, d, log, config)
            timings["sessions_s"] = time.monotonic() - t
    except WorldFailed as e:
        return record_failure(a, index, key, str(e), log, label)
    finally:
        for f in outs:
            if os.path.exists(f):
                os.remove(f)
        for mode in MODES:
            shutil.rmtree(os.path.join(scratch, f"state-{mode}"), ignore_errors=True)
    with open(os.path.join(d, "metrics.json")) as f:
        evaluated = json.load(f)
    runs = {r["mode"]: metrics_of(r) for r in evaluated["runs"]}
    if a.scenario == "kidnap":
        localisation = {r["mode"]: instants_of(r) for r in evaluated["runs"]}
    elif a.scenario == "restart":
        localisation = sessions
    else:
        localisation = None
    if a.scenario == "outliers":
        outliers = {kind: {r["mode"]: metrics_of(r) for r in read_json(path)["runs"]} for kind, path in outliers.items()}
    rec = {
        "index": index,
        "world_seed": seed,
        "key": key,
        **({"config": label} if label is not None else {}),
        "world": os.path.relpath(world, a.results),
        "generation": generation_of(generated),
        "modes": runs,
        "thresholds": thresholds_of(evaluated["params"]),
        "timings_s": {k: round(v, 2) for k, v in timings.items()},
        "localisation": localisation,
        **({"outliers": outliers} if a.scenario == "outliers" else {}),
        "rerun": f"vita-sim --generate-world --world-seed {seed} --family {a.family}{' --faults' if a.faults else ''}"
                 + (f" --kidnaps {1 if a.quick else KIDNAPS_PER_WORLD}" if a.scenario == "kidnap" else "") + " "
                 f"--output-world w.yaml && scripts/demo --world w.yaml --seed {seed}"
                 + (f" --laps {a.laps}" if a.laps else "") + (f" --config {config}" if label is not None else ""),
    }
    write_json(os.path.join(d, "world.json"), rec)  # a world is done only once this is written
    if os.path.exists(os.path.join(d, "failed.json")):
        os.remove(os.path.join(d, "failed.json"))
    return rec


def run_outliers(a, bins, seed, world, sim_log, outs, d, log, config):
    """--scenario outliers: the world's simulator log replayed again in every mode with wrong closures
    injected, each kind into its own metrics-<kind>.json. Returns those files by kind."""
    out = {}
    for kind in WRONG_CLOSURE_KINDS:
        try:
            for mode, o in zip(MODES, outs):
                run([os.path.join(bins, "slamd"), "--replay", sim_log, "--output", o, "--mode", mode, "--config",
                     config, "--robot", a.robot, "--inject-wrong-closures", kind, "--inject-seed", str(seed)], log)
            js = os.path.join(d, f"metrics-{kind}.json")
            evaluate = [os.path.join(bins, "vita-eval"), "--json", js]
            for o in outs:
                evaluate += ["--input", o]
            if not a.no_plots:
                evaluate += ["--plots", os.path.join(d, f"plots-{kind}"), "--world", world]
            run(evaluate, log)
            out[kind] = js
        finally:
            for f in outs:
                if os.path.exists(f):
                    os.remove(f)
    return out


def instants_of(run, session=None):
    """A run's localisation instants (kidnaps, session starts) as vita-eval judged them."""
    out = []
    for i in (run.get("localisation") or {}).get("instants", []):
        out.append({"kind": i["kind"], "t_s": i["t_s"], "session": session, "localised": i["localised"],
                    "laps": i["laps_to_localise"], "distance_m": i["distance_to_localise_m"],
                    "time_s": i["time_to_localise_s"], "false_localisations": i["false_localisations"],
                    "localising_s": i["localising_s"], "lem_after_m": i["lem_after_m"]})
    return out


def run_sessions(a, bins, seed, world, scratch, first_outs, d, log, config):
    """--scenario restart: sessions that start at drawn places of the world's path, each localising in
    the map its first run saved (slamd --map FILE --localise), in every mode. Returns each mode's
    localisation instants, one per session."""
    rng = random.Random(seed)
    out = {mode: [] for mode in MODES}
    for k in range(1, (1 if a.quick else RESTART_SESSIONS) + 1):
        phase = rng.uniform(0.0, 2.0 * math.pi)
        sim_log = os.path.join(scratch, "session.lcmlog")
        outs = [os.path.join(scratch, f"session-{mode}.lcmlog") for mode in MODES]
        try:
            run([os.path.join(bins, "vita-sim"), "--world", world, "--robot", a.robot, "--seed", str(seed + 7919 * k),
                 "--start-phase", f"{phase:.6f}", "--start-utime",
                 str(RESTART_SESSION_UTIME + k * RESTART_SESSION_UTIME_STEP), "--laps", str(RESTART_SESSION_LAPS),
                 "--output", sim_log, "--quiet"] + (["--camera-format", a.camera_format] if a.camera_format else []), log)
            for mode, o in zip(MODES, outs):
                state = os.path.join(scratch, f"state-{mode}")
                maps = sorted(f for f in os.listdir(state) if f.endswith(".vslam"))
                if not maps:
                    raise WorldFailed(f"slamd --mode {mode} saved no map in {state} (see {log})")
                run([os.path.join(bins, "slamd"), "--replay", sim_log, "--output", o, "--mode", mode, "--config",
                     config, "--robot", a.robot, "--map", os.path.join(state, maps[-1]), "--localise"], log)
            os.remove(sim_log)
            js = os.path.join(d, f"session-{k}.json")
            evaluate = [os.path.join(bins, "vita-eval"), "--json", js, "--session-start", "--map-truth",
                        first_outs[MODES.index("vita")]]
            for o in outs:
                evaluate += ["--input", o]
            if not a.no_plots and k == 1:
                evaluate += ["--plots", os.path.join(d, "plots-session-1"), "--world", world]
            run(evaluate, log)
        finally:
            for f in [sim_log] + outs:
                if os.path.exists(f):
                    os.remove(f)
        for r in read_json(js)["runs"]:
            out[r["mode"]] += instants_of(r, session=k)
    return out


def collect(a, key, label=None):
    """The finished worlds and the failed ones in DIR under config `label`, by index."""
    records, failed = [], []
    for i in range(1, a.worlds + 1):
        state, doc = world_state(a, i, key, label)
        if state == "done":
            records.append(doc)
        elif state == "failed":
            failed.append(doc)
    return records, failed
