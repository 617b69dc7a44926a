#!/usr/bin/python3
"""Plots a slamd output log with matplotlib: the final experience map (links, dense and sparse
experiences) over the pose trail coloured by time, the re-localisations, and the ground truth when
the log has it (a simulator run). An example of the whiskeye Python package (docs/python.md).

    plot_run.py slam.lcmlog                       # a window (needs a display)
    plot_run.py slam.lcmlog --output run.png      # a file (PNG, SVG or PDF, by its extension)

Needs Debian's python3-matplotlib. Without a display, --output writes the file all the same.
"""
import argparse
import bisect
import math
import sys

import whiskeye
import whiskeye.log
from whiskeye import channels


def load(path):
    """Trail (t, x, y), ground truth (x, y), the last map, the re-localisation events."""
    trail, truth, relocs = [], [], []
    last_map = None
    reader = whiskeye.log.read(path)
    for event in reader:
        if event.channel == channels.VITA_POSE:
            m = event.decode()
            trail.append((m.utime, m.x, m.y))
        elif event.channel == channels.GROUND_TRUTH:
            m = event.decode()
            truth.append((m.utime, m.x, m.y, m.theta))
        elif event.channel == channels.VITA_MAP:
            last_map = event.decode()
        elif event.channel == channels.VITA_EVENT:
            m = event.decode()
            if m.type == whiskeye.vita_event_t.RELOCALISE and m.to_id != m.from_id:
                relocs.append(m)
    if reader.damage:
        print("plot_run.py: %s (plotted what could be read)" % reader.damage, file=sys.stderr)
    return trail, truth, last_map, relocs


def align(truth, vmap):
    """vita-eval's alignment (docs/evaluation.md): the rigid transform putting the first experience on
    the ground truth at its creation time (here the nearest sample, not interpolated). Returns a
    function map (x, y) -> world (x, y), or None."""
    if not truth or vmap is None or not vmap.experiences:
        return None
    first = min(vmap.experiences, key=lambda e: (e.utime_created, e.id))
    times = [t for t, _, _, _ in truth]
    i = min(bisect.bisect_left(times, first.utime_created), len(truth) - 1)
    _, gx, gy, gth = truth[i]
    dth = gth - first.theta
    c, s = math.cos(dth), math.sin(dth)
    tx, ty = gx - (c * first.x - s * first.y), gy - (s * first.x + c * first.y)
    return lambda x, y: (tx + c * x - s * y, ty + s * x + c * y)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", help="slamd output log (slamd --replay ... --output LOG, or an lcm-logger recording)")
    parser.add_argument("--output", help="write the figure to this file instead of showing it")
    args = parser.parse_args()

    import matplotlib
    if args.output:
        matplotlib.use("Agg")  # no display needed to write a file
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    trail, truth, vmap, relocs = load(args.log)
    if not trail and vmap is None:
        sys.exit("plot_run.py: %s has no VITA_POSE and no VITA_MAP: not a slamd output log" % args.log)

    # With ground truth (a simulator run) everything is drawn in the world frame, aligned as vita-eval
    # aligns; without it, in slamd's map frame.
    to_world = align(sorted(truth), vmap)
    tf = to_world or (lambda x, y: (x, y))
    frame = "world frame (first experience on ground truth)" if to_world else "map frame"
    fig, ax = plt.subplots(figsize=(8, 7), constrained_layout=True)
    if truth:
        ax.plot([x for _, x, _, _ in truth], [y for _, _, y, _ in truth], color="0.7", lw=2, label="ground truth",
                zorder=1)
    if trail:
        t0 = trail[0][0]
        times = [(t - t0) * 1e-6 for t, _, _ in trail]
        points = [tf(x, y) for _, x, y in trail]
        # One segment per step, coloured by time; jumps (re-localisations) are not drawn as path.
        segments, seg_times = [], []
        for i in range(1, len(points)):
            (x0, y0), (x1, y1) = points[i - 1], points[i]
            if (x1 - x0) ** 2 + (y1 - y0) ** 2 < 0.2 ** 2:
                segments.append([(x0, y0), (x1, y1)])
                seg_times.append(times[i])
        lines = LineCollection(segments, cmap="viridis", linewidths=1.5, zorder=2)
        lines.set_array(seg_times)
        ax.add_collection(lines)
        fig.colorbar(lines, ax=ax, label="time since the first pose (s)", shrink=0.7)
    if vmap is not None:
        pose = {e.id: tf(e.x, e.y) for e in vmap.experiences}
        for link in vmap.links:
            a, b = pose.get(link.from_id), pose.get(link.to_id)
            if a and b:
                ax.plot([a[0], b[0]], [a[1], b[1]], color="tab:blue", lw=0.6, zorder=3)
        dense = [pose[e.id] for e in vmap.experiences if e.dense]
        sparse = [pose[e.id] for e in vmap.experiences if not e.dense]
        ax.scatter([x for x, _ in sparse], [y for _, y in sparse], s=14, facecolors="none", edgecolors="tab:blue",
                   label="sparse experience", zorder=4)
        ax.scatter([x for x, _ in dense], [y for _, y in dense], s=18, color="tab:orange",
                   label="dense experience (contacts)", zorder=4)
        targets = [pose[r.to_id] for r in relocs if r.to_id in pose]
        ax.scatter([x for x, _ in targets], [y for _, y in targets], s=60, facecolors="none", edgecolors="magenta",
                   label="re-localisation target (%d events)" % len(relocs), zorder=5)
    mode = {0: "visual", 1: "tactile", 2: "vita"}.get(vmap.mode if vmap is not None else -1, "unknown")
    ax.set_title("%s: %s mode, %d experiences" % (args.log, mode, len(vmap.experiences) if vmap else 0))
    ax.set_xlabel("x (m), " + frame)
    ax.set_ylabel("y (m)")
    ax.set_aspect("equal")
    ax.autoscale()
    ax.grid(True, color="0.9")
    ax.legend(loc="best", fontsize="small")
    if args.output:
        fig.savefig(args.output, dpi=120)
        print("plot_run.py: wrote %s" % args.output)
    else:
        plt.show()


if __name__ == "__main__":
    main()
