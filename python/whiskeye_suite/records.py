"""Reading a world's record (world.json) or failure (failed.json) back from the results folder: the
aggregation trusts every field it uses, so a record is checked whole before it is used. A file that
is not such a record (not a regular file, not JSON, nested or sized beyond any record, a NaN or a
number beyond a double's range, a missing key, a value of the wrong type) is refused with one line
naming the file and the field (BadRecord), never a traceback half-way through the summary."""
import json
import math
import os
import stat

from .common import MODES, WRONG_CLOSURE_KINDS

MAX_RECORD_BYTES = 64 << 20  # a restart suite's world.json is tens of kB
MAX_DEPTH = 32  # a record nests 5 deep
MAX_INT = 2**63  # counts, seeds and indices are int64 in the programs that make them
MAX_MAGNITUDE = 1e100  # any measure a record holds is far below; sums and differences of such stay finite


class BadRecord(Exception):
    """A results file the suite cannot use: str() is the one line "PATH: what is wrong"."""


class _NonFinite:
    """A JSON number that is no double: NaN, Infinity, -Infinity (Python's extensions) or a literal
    beyond a double's range (1e400), kept as written so the refusal can show it."""
    def __init__(self, text):
        self.text = text


def _float(text):
    v = float(text)
    return v if math.isfinite(v) else _NonFinite(text)


def shown(v, limit=40):
    """A value as a line shows it: at most `limit` characters."""
    text = v.text if isinstance(v, _NonFinite) else json.dumps(v) if isinstance(v, str) else repr(v)
    if isinstance(v, int) and not isinstance(v, bool) and len(text) > limit:
        return f"an integer of {len(text.lstrip('-'))} digits"
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _walk(doc):
    """Every value with its path (modes.vita.ate, localisation.vita[0].t_s), refusing what no record
    holds anywhere: nesting beyond MAX_DEPTH, a non-finite number, a number beyond the bounds.
    Iterative: a deep document must not exhaust Python's stack here either."""
    stack = [("", doc, 0)]
    while stack:
        path, v, depth = stack.pop()
        if depth > MAX_DEPTH:
            where = path.split("[")[0].split(".")[0] or "the document"
            raise ValueError(f"{where}: nested more than {MAX_DEPTH} deep (a record nests a few levels)")
        if isinstance(v, _NonFinite):
            raise ValueError(f"{path} is {v.text}: not a finite number (a record holds finite numbers, null for n/a)")
        if isinstance(v, bool) or v is None or isinstance(v, str):
            continue
        if isinstance(v, int):
            if abs(v) >= MAX_INT:
                raise ValueError(f"{path} is {shown(v)}: beyond the 64-bit range of any count a record holds")
        elif isinstance(v, float):
            if abs(v) > MAX_MAGNITUDE:
                raise ValueError(f"{path} is {shown(v)}: beyond {MAX_MAGNITUDE:g}, no measure a record holds")
        elif isinstance(v, dict):
            stack += reversed([(f"{path}.{k}" if path else k, x, depth + 1) for k, x in v.items()])
        elif isinstance(v, list):
            stack += reversed([(f"{path}[{n}]", x, depth + 1) for n, x in enumerate(v)])


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


# What each field may be: a type check and its description for the refusal.
NUMBER = (_is_number, "a number")
NUMBER_OR_NULL = (lambda v: v is None or _is_number(v), "a number or null")
INT = (lambda v: isinstance(v, int) and not isinstance(v, bool), "an integer")
INT_OR_NULL = (lambda v: v is None or (isinstance(v, int) and not isinstance(v, bool)), "an integer or null")
STRING = (lambda v: isinstance(v, str), "a string")
STRING_OR_NULL = (lambda v: v is None or isinstance(v, str), "a string or null")
BOOL = (lambda v: isinstance(v, bool), "true or false")
SCALAR = (lambda v: v is None or isinstance(v, (str, int, float)), "a string, a number, a boolean or null")
OBJECT = (lambda v: isinstance(v, dict), "an object")
OBJECT_OR_NULL = (lambda v: v is None or isinstance(v, dict), "an object or null")
LIST = (lambda v: isinstance(v, list), "a list")

# A mode's metrics (pipeline.metrics_of): required, then optional (older records lack some).
MODE_FIELDS = {"arr": NUMBER_OR_NULL, "arcr": NUMBER_OR_NULL, "ate": NUMBER_OR_NULL, "lem": NUMBER_OR_NULL,
               "enm": NUMBER_OR_NULL, "false_closures": INT_OR_NULL}
MODE_OPTIONAL = {"experiences": INT_OR_NULL, "links_revoked": INT_OR_NULL, "relocalisations": INT_OR_NULL,
                 "false_closure_worst_m": NUMBER_OR_NULL, "neighbour_misses": INT_OR_NULL,
                 "neighbour_miss_share": NUMBER_OR_NULL, "spacing_m": NUMBER_OR_NULL, "spacing_deg": NUMBER_OR_NULL,
                 "ate_windows": LIST, "links_wrong": INT_OR_NULL, "links_wrong_kept": INT_OR_NULL,
                 "links_right_revoked": INT_OR_NULL}
THRESHOLD_FIELDS = {k: NUMBER for k in ("correct_m", "correct_deg", "false_closure_m", "false_closure_deg")}
# A localisation instant (pipeline.instants_of).
INSTANT_FIELDS = {"t_s": NUMBER, "session": INT_OR_NULL, "localised": BOOL, "laps": NUMBER_OR_NULL,
                  "false_localisations": INT, "localising_s": NUMBER_OR_NULL, "lem_after_m": NUMBER_OR_NULL}
INSTANT_OPTIONAL = {"kind": STRING, "distance_m": NUMBER_OR_NULL, "time_s": NUMBER_OR_NULL}
GENERATION_FIELDS = {"arena_side": NUMBER_OR_NULL, "trajectory.radius": NUMBER_OR_NULL,
                     "trajectory.speed": NUMBER_OR_NULL, "trajectory.laps": NUMBER_OR_NULL,
                     "trajectory.direction": SCALAR, "tactile_landmarks": SCALAR}


def _fields(obj, path, required, optional=None):
    for k, (ok, what) in required.items():
        if k not in obj:
            raise ValueError(f"{path}{k} is missing")
        if not ok(obj[k]):
            raise ValueError(f"{path}{k} is {shown(obj[k])}: not {what}")
    for k, (ok, what) in (optional or {}).items():
        if k in obj and not ok(obj[k]):
            raise ValueError(f"{path}{k} is {shown(obj[k])}: not {what}")


def _object(obj, path, key, check=OBJECT):
    if key not in obj:
        raise ValueError(f"{path}{key} is missing")
    if not check[0](obj[key]):
        raise ValueError(f"{path}{key} is {shown(obj[key])}: not {check[1]}")
    return obj[key]


def check_modes(modes, path):
    """Every mode's metrics (pipeline.metrics_of) under `path`."""
    for m in MODES:
        run = _object(modes, path, m)
        _fields(run, f"{path}{m}.", MODE_FIELDS, MODE_OPTIONAL)
        for n, x in enumerate(run.get("ate_windows") or []):
            if not NUMBER_OR_NULL[0](x):
                raise ValueError(f"{path}{m}.ate_windows[{n}] is {shown(x)}: not {NUMBER_OR_NULL[1]}")


def check_world(doc):
    """world.json's fields the aggregation, the summary and the plots use."""
    _fields(doc, "", {"index": INT, "world_seed": INT, "rerun": STRING},
            {"key": STRING_OR_NULL, "config": STRING, "world": STRING})
    gen = _object(doc, "", "generation")
    _fields(gen, "generation.", {}, GENERATION_FIELDS)
    check_modes(_object(doc, "", "modes"), "modes.")
    outliers = doc.get("outliers")
    if outliers is not None:  # --scenario outliers: every mode's metrics under each kind injected
        _object(doc, "", "outliers", OBJECT_OR_NULL)
        for kind in WRONG_CLOSURE_KINDS:
            check_modes(_object(outliers, "outliers.", kind), f"outliers.{kind}.")
    if doc.get("thresholds") is not None:
        _fields(_object(doc, "", "thresholds", OBJECT_OR_NULL), "thresholds.", THRESHOLD_FIELDS)
    if doc.get("timings_s") is not None:
        for k, v in _object(doc, "", "timings_s", OBJECT_OR_NULL).items():
            if not _is_number(v):
                raise ValueError(f"timings_s.{k} is {shown(v)}: not a number")
    loc = doc.get("localisation")
    if loc is not None:
        _object(doc, "", "localisation", OBJECT_OR_NULL)
        counts = set()
        for m in MODES:
            ins = _object(loc, "localisation.", m, LIST)
            counts.add(len(ins))
            for n, i in enumerate(ins):
                if not isinstance(i, dict):
                    raise ValueError(f"localisation.{m}[{n}] is {shown(i)}: not an object")
                _fields(i, f"localisation.{m}[{n}].", INSTANT_FIELDS, INSTANT_OPTIONAL)
        if len(counts) > 1:
            raise ValueError("localisation: the modes have different numbers of instants "
                             f"({', '.join(f'{m} {len(loc[m])}' for m in MODES)}): each mode is judged at the same ones")


def check_failure(doc):
    """failed.json's fields."""
    _fields(doc, "", {"index": INT, "world_seed": INT, "failed": STRING},
            {"key": STRING_OR_NULL, "config": STRING, "log": STRING, "placeholder": BOOL})


def read_record(path, index, kind):
    """The record at `path` (kind "world" for world.json, "failed" for failed.json) of world `index`,
    checked; None when there is no such file. Raises BadRecord naming the file and what is wrong."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)  # a FIFO must not block the suite
    except FileNotFoundError:
        if os.path.islink(path):
            raise BadRecord(f"{path}: a symbolic link to {os.readlink(path)}, which does not exist") from None
        return None
    except OSError as e:
        raise BadRecord(f"{path}: cannot be read: {e.strerror}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise BadRecord(f"{path}: not a regular file")
        if st.st_size > MAX_RECORD_BYTES:
            raise BadRecord(f"{path}: {st.st_size} bytes, more than any record ({MAX_RECORD_BYTES >> 20} MiB at most)")
        with os.fdopen(fd, "rb", closefd=False) as f:
            data = f.read(MAX_RECORD_BYTES + 1)
    except OSError as e:
        raise BadRecord(f"{path}: cannot be read: {e.strerror}") from None
    finally:
        os.close(fd)
    if not data:
        raise BadRecord(f"{path}: empty (0 bytes): no record")
    if len(data) > MAX_RECORD_BYTES:
        raise BadRecord(f"{path}: more than any record ({MAX_RECORD_BYTES >> 20} MiB at most)")
    try:
        doc = json.loads(data.decode("utf-8"), parse_constant=_NonFinite, parse_float=_float)
    except UnicodeDecodeError as e:
        raise BadRecord(f"{path}: not a JSON record: not UTF-8 (byte {e.start})") from None
    except RecursionError:
        raise BadRecord(f"{path}: not a JSON record: nested too deeply to read (a record nests a few levels)") from None
    except json.JSONDecodeError as e:
        raise BadRecord(f"{path}: not a JSON record: {e}") from None
    except ValueError:  # an integer beyond Python's limit on digits (4300)
        raise BadRecord(f"{path}: not a JSON record: an integer of thousands of digits") from None
    try:
        if not isinstance(doc, dict):
            raise ValueError(f"the document is {shown(doc)}: not an object")
        _walk(doc)
        (check_world if kind == "world" else check_failure)(doc)
        if doc["index"] != index:
            raise ValueError(f"index is {doc['index']}, but the record is world {index}'s")
    except ValueError as e:
        raise BadRecord(f"{path}: {e}") from None
    return doc
