"""Distributions over worlds: median, the 10th percentile on the bad side, the worst."""
import math


def percentile(values, q):
    """Linear-interpolation percentile (numpy's default) of a non-empty list."""
    v = sorted(values)
    pos = (len(v) - 1) * q / 100.0
    lo = math.floor(pos)
    hi = min(lo + 1, len(v) - 1)
    return v[lo] + (v[hi] - v[lo]) * (pos - lo)


def distribution(values, better):
    """median, the 10th percentile on the bad side, and the worst; n/a values counted apart."""
    vals = [v for v in values if v is not None]
    if not vals:
        return {"median": None, "p10": None, "worst": None, "n": 0, "undefined": len(values)}
    bad_side = 10 if better == "high" else 90
    return {"median": percentile(vals, 50), "p10": percentile(vals, bad_side),
            "worst": min(vals) if better == "high" else max(vals), "n": len(vals), "undefined": len(values) - len(vals)}
