"""Results of slow, deterministic computations, cached on disk and keyed by everything they depend on.

The cache folder is ``$DOUBLE_PENDULUM_CACHE`` if set, else ``.cache/`` in the working directory (not
committed); each kind of result has its own subfolder (``references/``, ``loss_fits/``). A result is
stored under a hash of its inputs and of the sources that compute it (:func:`sources_hash`: the
runtime and the analysis package), so a change of the equations, the integrators or the fitting code
computes it anew; a cached result is the computed one, byte for byte. Delete the folder to force a
recomputation by hand.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import pickle
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")

CACHE_ENV = "DOUBLE_PENDULUM_CACHE"
"""Environment variable naming the cache folder."""
_SOURCES = ("model", "solvers", "component", "analysis")


def cache_root() -> Path:
    """The cache folder: ``$DOUBLE_PENDULUM_CACHE`` or ``.cache`` (relative to the working directory)."""
    return Path(os.environ.get(CACHE_ENV) or ".cache")


@functools.cache
def sources_hash(packages: tuple[str, ...] = _SOURCES) -> str:
    """Hash of the package's sources in ``packages`` (subpackage names under ``double_pendulum``)."""
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def key_hash(key: Mapping[str, Any]) -> str:
    """Hash of a JSON-serialisable key (sorted keys)."""
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]


def cached(kind: str, key: Mapping[str, Any], compute: Callable[[], T]) -> T:
    """``compute()``, or its result stored earlier under ``kind`` and ``key`` (plus :func:`sources_hash`).

    The result is pickled to ``<cache>/<kind>/<hash>.pkl``, written whole and then renamed, so a
    parallel or interrupted run never leaves a partial file; a damaged file is computed anew.
    """
    path = cache_root() / kind / f"{key_hash({**key, 'sources': sources_hash()})}.pkl"
    if path.is_file():
        try:
            with path.open("rb") as f:
                return pickle.load(f)
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ImportError):
            pass  # damaged or from an incompatible version: compute anew
    result = compute()
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.stem}.{os.getpid()}.pkl")
    with partial.open("wb") as f:
        pickle.dump(result, f)
    os.replace(partial, path)
    return result
