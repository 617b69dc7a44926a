"""The suite's plots: each metric's distribution per mode, and ARR against ARCR per world."""
import math
import os
import sys

from .common import METRICS, MODES


def write_plots(worlds, a, summary_targets):
    """Each metric's distribution per mode, and ARR against ARCR per world (ViTa by its targets)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("suite: no matplotlib (scripts/install-deps installs python3-matplotlib): no plots", file=sys.stderr)
        return []
    d = os.path.join(a.results, "plots")
    os.makedirs(d, exist_ok=True)
    written = []
    colours = {"visual": "tab:blue", "tactile": "tab:orange", "vita": "tab:green"}
    fig, axes = plt.subplots(1, len(METRICS), figsize=(4 * len(METRICS), 4))
    for ax, (key, label, better) in zip(axes, METRICS):
        data = [[w["modes"][m][key] for w in worlds if w["modes"][m][key] is not None] for m in MODES]
        pos = [i + 1 for i, x in enumerate(data) if x]
        if pos:
            ax.boxplot([x for x in data if x], positions=pos, widths=0.5, showfliers=False)
        else:
            ax.text(0.5, 0.5, "n/a in every run", transform=ax.transAxes, ha="center")
        for i, (m, x) in enumerate(zip(MODES, data)):
            jitter = [i + 1 + 0.15 * math.sin(7.3 * k) for k in range(len(x))]
            ax.scatter(jitter, x, s=12, color=colours[m], alpha=0.8, zorder=3)
        ax.set_xticks(range(1, len(MODES) + 1), MODES)
        ax.set_title(f"{label} ({'higher' if better == 'high' else 'lower'} is better)", fontsize=9)
        if key in ("enm",) and all(v > 0 for x in data for v in x) and any(data):
            ax.set_yscale("log")
        ax.grid(alpha=0.3)
    fig.suptitle(f"{len(worlds)} worlds, family {a.family}{' with faults' if a.faults else ''}, suite seed {a.suite_seed}")
    fig.tight_layout()
    path = os.path.join(d, "metrics_by_mode.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    written.append(path)

    fig, ax = plt.subplots(figsize=(6, 5))
    for m in ("visual", "tactile"):
        pts = [(w["modes"][m]["arr"], w["modes"][m]["arcr"]) for w in worlds
               if w["modes"][m]["arr"] is not None and w["modes"][m]["arcr"] is not None]
        if pts:
            ax.scatter(*zip(*pts), s=18, color=colours[m], alpha=0.6, label=m)
    for ok, colour, label in ((True, "tab:green", "vita, targets met"), (False, "tab:red", "vita, a target missed")):
        pts = [(w["modes"]["vita"]["arr"], w["modes"]["vita"]["arcr"]) for w in worlds
               if summary_targets.get(w["index"]) == ok and w["modes"]["vita"]["arr"] is not None
               and w["modes"]["vita"]["arcr"] is not None]
        if pts:
            ax.scatter(*zip(*pts), s=40, marker="D", color=colour, label=label, edgecolor="black", linewidth=0.5)
    ax.set_xlabel("ARR (re-localisation rate)")
    ax.set_ylabel("ARCR (correct re-localisations)")
    ax.set_xlim(-0.02, 1.02)
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8, loc="lower left")
    else:
        ax.text(0.5, 0.5, "ARR or ARCR n/a in every run", transform=ax.transAxes, ha="center")
    ax.set_title("ARR against ARCR per world")
    fig.tight_layout()
    path = os.path.join(d, "arr_vs_arcr.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    written.append(path)
    return written
