"""How many processes a run uses at a time: one per core this process may use, at most ``$DOUBLE_PENDULUM_WORKERS``.

``run all`` starts one child process per core and sets the variable to 1 in its children
(:func:`double_pendulum.runs.pool.child_environment`), so that each child runs its sweeps in itself; a
scenario run on its own runs its sweeps on one worker process per core
(:mod:`double_pendulum.analysis.sweep`).
"""

from __future__ import annotations

import os

WORKERS_ENV = "DOUBLE_PENDULUM_WORKERS"
"""Environment variable capping the worker processes of every sweep (``run all`` sets it to 1 in its
children, which already run one per core)."""


def default_workers() -> int:
    """Number of worker processes a sweep uses by default: the cores this process may use, at most
    ``$DOUBLE_PENDULUM_WORKERS`` when that is set to a positive integer."""
    try:
        cores = max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        cores = max(1, os.cpu_count() or 1)
    cap = os.environ.get(WORKERS_ENV, "").strip()
    return min(cores, int(cap)) if cap.isdigit() and int(cap) > 0 else cores
