"""What every part of the suite shares: the repository's paths, the programs, modes, scenarios and
metrics, the one-line error exit, number formatting and the atomic JSON files of the results."""
import hashlib
import json
import math
import os
import secrets
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "suite")  # the entry point the Slurm jobs call back into
PROGRAMS = ("vita-sim", "slamd", "vita-eval")
MODES = ("visual", "tactile", "vita")
SCENARIOS = ("normal", "kidnap", "restart", "outliers", "long")
LONG_RUN_LAPS = 40  # --scenario long: every world driven this many laps (--quick: 8)
# --scenario outliers: each world's run replayed again with one wrong closure added per closure the SLAM
# makes (slamd --inject-wrong-closures), of each kind, and compared with the clean run.
WRONG_CLOSURE_KINDS = ("random", "group")
KIDNAPS_PER_WORLD = 3  # --scenario kidnap (1 with --quick)
RESTART_SESSIONS = 4  # --scenario restart: sessions localising in each world's map (1 with --quick) ...
RESTART_SESSION_LAPS = 2  # ... each this many laps
# A session's clock: its first utime, far after any first session's (vita-sim's default start plus
# < 10^4 s), so that the map's experiences and the session's events never share a time.
RESTART_SESSION_UTIME = 2_000_000_000_000_000
RESTART_SESSION_UTIME_STEP = 10_000_000_000  # us between sessions


def world_seed(suite_seed, index):
    """World `index` (1-based) of suite seed `suite_seed`: the seed vita-sim draws it from."""
    return suite_seed * 1000 + index


METRICS = (  # key, label, better
    ("arr", "ARR", "high"),
    ("arcr", "ARCR", "high"),
    ("ate", "ATE RMSE (m)", "low"),
    ("lem", "paper's LEM pos RMSE (m)", "low"),
    ("enm", "EnM", "low"),
    ("false_closures", "false closures", "low"),
)


def fail(msg, status=2):
    print(f"suite: {msg}", file=sys.stderr)
    sys.exit(status)


def fmt(v, spec=".4f"):
    return "n/a" if v is None else format(v, spec)


def file_digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()[:16]


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


class NotJson(Exception):
    """A document write_json refuses: str() is the one line "PATH: FIELD is nan: ..."."""


def nonfinite_path(doc):
    """The path of the first number in `doc` that standard JSON cannot hold (NaN, ±inf), or None."""
    stack = [("", doc)]
    while stack:
        p, v = stack.pop()
        if isinstance(v, float) and not math.isfinite(v):
            return p or "the document", v
        if isinstance(v, dict):
            stack += reversed([(f"{p}.{k}" if p else str(k), x) for k, x in v.items()])
        elif isinstance(v, (list, tuple)):
            stack += reversed([(f"{p}[{n}]", x) for n, x in enumerate(v)])
    return None


def write_json(path, doc):
    """Standard JSON (RFC 8259): a non-finite number, which Python's json would write as NaN or
    Infinity that no other reader takes, is refused naming its field (NotJson), before anything is
    written. Atomically: a reader (another node, the aggregation) sees the old file or the whole new one. The
    temp file beside it is this writer's own (created exclusive, a random name: two suites writing one
    results folder no longer share one, which tore the file and made the second rename fail), synced
    before the rename and the folder after it, so a node that crashes leaves one of the two as well."""
    bad = nonfinite_path(doc)
    if bad is not None:
        raise NotJson(f"{path}: {bad[0]} is {bad[1]}: not a finite number, which JSON cannot hold; nothing written")
    d = os.path.dirname(path) or "."
    while True:
        tmp = os.path.join(d, f".{os.path.basename(path)}.{secrets.token_hex(8)}.tmp")
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
            break
        except FileExistsError:
            continue
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(doc, f, indent=1, sort_keys=True, allow_nan=False)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    folder = os.open(d, os.O_RDONLY | os.O_DIRECTORY)
    try:
        os.fsync(folder)
    finally:
        os.close(folder)
