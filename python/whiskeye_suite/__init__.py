"""The world suite (docs/evaluation.md, "The world suite"): scripts/suite is its entry point.

cli: options; pipeline: one world's job and its record; local, slurm: the executors; stats,
targets: distributions and the --check targets; report, plots: the summary. A development tool,
not installed with the whiskeye package: standard library only, matplotlib for the plots.
"""
