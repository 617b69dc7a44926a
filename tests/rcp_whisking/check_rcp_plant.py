#!/usr/bin/env python3
"""Runs rcp-plant on the example scenario and checks its JSON: valid, complete, and RCP doing its job."""
import json
import subprocess
import sys

binary, scenario, config = sys.argv[1:4]
out = subprocess.run([binary, "--scenario", scenario, "--config", config, "--cycles", "8"],
                     check=True, capture_output=True, text=True).stdout
d = json.loads(out)
for run in ("with_rcp", "without_rcp"):
    for key in ("contact_rate", "peak_deflection", "reaction_latency_mean_ms", "false_contacts"):
        assert key in d[run], f"{run}.{key} missing"
assert d["cycles"] == 8, d["cycles"]
assert d["with_rcp"]["cycles_measured"] == 7, d["with_rcp"]["cycles_measured"]
assert d["with_rcp"]["contact_rate"] >= 0.95, d["with_rcp"]["contact_rate"]
assert d["peak_reduction"] >= 0.5, d["peak_reduction"]
assert d["with_rcp"]["false_contacts"] == 0
print("ok")
