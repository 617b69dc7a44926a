"""The local executor: the worlds on this machine, --jobs at once, the logs in a scratch folder."""
import concurrent.futures
import os
import shutil
import tempfile

from .pipeline import run_world, world_dir


def scratch_for(a, index):
    """Where world `index`'s simulator and replay logs go: its own folder under --scratch (a Slurm
    task: $TMPDIR or /tmp, node-local), else the world's folder."""
    root = a.scratch or (tempfile.gettempdir() if a.run_world is not None else None)
    if root is None:
        return world_dir(a, index), lambda: None
    os.makedirs(root, exist_ok=True)
    d = tempfile.mkdtemp(prefix=f"suite-world-{index:03d}-", dir=root)
    return d, lambda: shutil.rmtree(d, ignore_errors=True)


def run_one(a, bins, index, keys):
    """World `index` under every config: their records or failures, in the order of a.variants."""
    scratch, cleanup = scratch_for(a, index)
    try:
        return run_world(a, bins, index, keys, scratch)
    finally:
        cleanup()


def run_local(a, bins, keys, todo, progress):
    """Every world of `todo` on this machine, --jobs at once."""
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        for fut in concurrent.futures.as_completed([pool.submit(run_one, a, bins, i, keys) for i in todo]):
            for doc in fut.result():
                progress.world(doc)
