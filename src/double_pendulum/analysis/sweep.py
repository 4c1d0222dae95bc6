"""Many FMU runs at once: parameter sweeps on all local cores or on a Dask cluster.

:func:`run_sweep` runs the FMU once per *case* (a mapping of start values, as for
:meth:`double_pendulum.fmu.running.runner.FmuRunner.simulate`) and returns the results in the order of the
cases. The cases are split into contiguous chunks; each worker process extracts the FMU once
(one :class:`~double_pendulum.fmu.running.runner.FmuRunner` per process, kept for later chunks) and runs its
chunks one case after another.

* Locally (default) the chunks go to a :class:`concurrent.futures.ProcessPoolExecutor` with one
  process per core (``max_workers=None``), started by ``spawn`` so no threads of the calling
  process are forked and the workers are the caller's own children (their CPU time counts in the
  caller's ``RUSAGE_CHILDREN`` and in ``time``); ``max_workers=1`` runs in the calling process. As
  with any spawned worker processes, a script that calls this must guard its top level with
  ``if __name__ == "__main__":``.
* With ``scheduler="tcp://host:8786"`` (or a ``distributed.Client``) they go to a Dask cluster,
  as in FMPy's own parameter-variation example. The FMU file itself is sent to the workers once
  (``Client.scatter(..., broadcast=True)``), so they need not share a file system; they need this
  package and fmpy installed (``pip install double-pendulum-fmu``).

Deterministic: the cases are fixed before anything is distributed (:func:`random_cases` draws
them from a seeded generator), every run is deterministic, and results are put back in case
order, so the same cases give bit-identical results with any number of workers, locally or on
Dask. Long runs show a tqdm progress bar on stderr (rate and time left).
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import math
import multiprocessing
import multiprocessing.util
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..fmu.running.runner import FmuRunError, FmuRunner
from ..runs.interrupts import acknowledge, sigint_blocked, worker_ignores_sigint
from ..runs.progress import progress_bar as _progress_bar
from ..runs.workers import default_workers

CHUNKS_PER_WORKER = 4


def chunk(items: Sequence[Any], n_chunks: int) -> list[list[Any]]:
    """Split ``items`` into at most ``n_chunks`` contiguous, nearly equal parts (order kept)."""
    n_chunks = max(1, min(n_chunks, len(items)))
    size, extra = divmod(len(items), n_chunks)
    out, start = [], 0
    for i in range(n_chunks):
        stop = start + size + (1 if i < extra else 0)
        out.append(list(items[start:stop]))
        start = stop
    return out


# ---------------------------------------------------------------------------- generic parallel map
def _dask_client(scheduler: Any):
    """Return ``(client, owned)`` for a scheduler address or an existing ``distributed.Client``."""
    try:
        from distributed import Client
    except ImportError as error:  # pragma: no cover - depends on the installation
        raise ImportError("running on a Dask cluster needs 'dask[distributed]' installed") from error
    if isinstance(scheduler, Client):
        return scheduler, False
    return Client(scheduler), True


def _is_fmu_resources(entry: str) -> bool:
    """True for the ``resources`` folder of an extracted FMU (pythonfmu puts it on ``sys.path``)."""
    path = Path(entry)
    return path.name == "resources" and (path.parent / "modelDescription.xml").is_file()


@contextlib.contextmanager
def _without_fmu_resources_on_path() -> Iterator[None]:
    """Hide extracted FMUs' ``resources`` folders from ``sys.path`` while worker processes start.

    Running a pythonfmu FMU in this process appends its ``resources`` folder (which holds a bundled
    copy of this package) to ``sys.path`` for good; spawned workers copy ``sys.path`` and would
    otherwise import that copy instead of the installed package.
    """
    saved = list(sys.path)
    sys.path[:] = [p for p in saved if not _is_fmu_resources(p)]
    try:
        yield
    finally:
        sys.path[:] = saved


def _call(func: Callable[..., Any], item: Any, shared: Any) -> Any:
    return func(item) if shared is None else func(item, shared)


def progress_bar(total: int, label: str, *, enabled: bool | None = None, unit: str = "run") -> Any:
    """A progress counter on stderr (:func:`double_pendulum.runs.progress.progress_bar`): a tqdm bar
    on a terminal or in a notebook, a few plain lines for long loops otherwise."""
    return _progress_bar(total, label, enabled=enabled, unit=unit)


@dataclass(frozen=True)
class WorkerPool:
    """Local worker processes kept for several :func:`parallel_map` calls (:func:`worker_pool`): each
    spawned worker imports the package once (about 3 s of CPU) instead of once per call."""

    executor: ProcessPoolExecutor
    workers: int


STOP_WORKERS_S = 2.0
"""How long [s] stopped workers may take to end after SIGTERM before they are killed."""


def stop_workers(executor: ProcessPoolExecutor) -> None:
    """End ``executor``'s worker processes now (SIGTERM, SIGKILL after :data:`STOP_WORKERS_S`) and drop the
    work not yet done, instead of waiting for it as ``shutdown`` does: after Ctrl-C or a failed item."""
    processes = list((getattr(executor, "_processes", None) or {}).values())  # no public way to reach them
    for process in processes:
        process.terminate()
    executor.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + STOP_WORKERS_S
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
            process.join()
    executor.shutdown(wait=True)


@contextlib.contextmanager
def worker_pool(max_workers: int | None = None, n_items: int | None = None) -> Iterator[WorkerPool | None]:
    """A :class:`WorkerPool` of ``max_workers`` spawned processes (None: one per core; at most ``n_items``),
    shut down on exit; ``None`` when one worker would do (callers then run in this process).

    The workers ignore Ctrl-C; if the block ends with an exception (Ctrl-C, a failed item) they are stopped
    at once (:func:`stop_workers`), so no worker outlives the call or computes what nobody will read."""
    workers = default_workers() if max_workers is None else max_workers
    if n_items is not None:
        workers = min(workers, max(n_items, 1))
    if workers <= 1:
        yield None
        return
    executor = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=worker_ignores_sigint)  # fmt: skip
    try:
        yield WorkerPool(executor, workers)
    except BaseException as error:
        if isinstance(error, KeyboardInterrupt):
            acknowledge()
        stop_workers(executor)
        raise
    executor.shutdown(wait=True)


def parallel_map(
    func: Callable[..., Any],
    items: Sequence[Any],
    *,
    shared: Any = None,
    max_workers: int | None = None,
    scheduler: Any = None,
    progress: bool | None = None,
    label: str = "parallel",
    weights: Sequence[int] | None = None,
    unit: str = "run",
    pool: WorkerPool | None = None,
) -> tuple[list[Any], int]:
    """Apply ``func`` to every item in parallel; return ``(results in item order, workers used)``.

    ``func(item)``, or ``func(item, shared)`` when ``shared`` is given (sent to Dask workers once).
    ``func`` must be importable (a module-level function). ``max_workers=None`` uses every local
    core, ``1`` runs in this process; ``scheduler`` (address or ``distributed.Client``) uses Dask;
    ``pool`` (:func:`worker_pool`) reuses running local workers (``max_workers`` is then ignored).
    ``weights`` (default 1 each) count each item's share of the progress bar.
    """
    weights = list(weights) if weights is not None else [1] * len(items)
    results: list[Any] = [None] * len(items)
    with progress_bar(sum(weights), label, enabled=progress, unit=unit) as bar:
        if scheduler is not None:
            return _dask_map(func, items, shared, scheduler, bar, weights, results)
        with contextlib.ExitStack() as stack:
            if pool is None:  # a pool of this call's own
                pool = stack.enter_context(worker_pool(max_workers, len(items)))
            workers = 1 if pool is None else min(pool.workers, max(len(items), 1))
            if workers <= 1:
                for i, item in enumerate(items):
                    results[i] = _call(func, item, shared)
                    bar.update(weights[i])
                return results, 1
            with _without_fmu_resources_on_path(), sigint_blocked():  # workers start on these submits
                futures = {pool.executor.submit(_call, func, item, shared): i for i, item in enumerate(items)}
            for future in as_completed(futures):
                i = futures[future]
                results[i] = future.result()
                bar.update(weights[i])
        return results, workers


def _dask_map(func, items, shared, scheduler, bar, weights, results) -> tuple[list[Any], int]:
    from distributed import as_completed as dask_as_completed

    client, owned = _dask_client(scheduler)
    try:
        shared_ref = client.scatter(shared, broadcast=True) if shared is not None else None
        futures = [client.submit(_call, func, item, shared_ref, pure=False) for item in items]
        index = {future.key: i for i, future in enumerate(futures)}
        for future in dask_as_completed(futures):
            i = index[future.key]
            results[i] = future.result()
            bar.update(weights[i])
        workers = len(client.scheduler_info().get("workers", {})) or 1
    finally:
        if owned:
            client.close()
    return results, workers


# ---------------------------------------------------------------------------- FMU sweeps
@dataclass(frozen=True)
class FmuSource:
    """The FMU for the workers: a path (local processes) or the file's bytes (Dask), with its hash."""

    key: str
    path: str | None = None
    content: bytes | None = None

    @classmethod
    def from_path(cls, path: str | Path, *, embed: bool) -> FmuSource:
        data = Path(path).read_bytes()
        key = hashlib.sha256(data).hexdigest()[:16]
        return cls(key, str(Path(path).resolve()), data if embed else None)


_RUNNERS: dict[str, tuple[FmuRunner, threading.Lock]] = {}
_RUNNERS_LOCK = threading.Lock()


def process_runner(key: str, path: Callable[[], str]) -> tuple[FmuRunner, threading.Lock]:
    """This process's runner for the FMU ``key`` (extracted from ``path()`` on first use, kept for later
    calls, removed by :func:`close_runners` or at the exit of a worker process) and the lock that makes
    its calls one at a time."""
    with _RUNNERS_LOCK:
        if key not in _RUNNERS:
            runner = FmuRunner(path())
            multiprocessing.util.Finalize(runner, runner.close, exitpriority=10)
            _RUNNERS[key] = (runner, threading.Lock())
        return _RUNNERS[key]


def close_runners() -> None:
    """Close this process's runners (:func:`process_runner`): their extracted FMUs leave the temporary folder.
    A run calls it when it ends (its main process exits without running exit handlers)."""
    with _RUNNERS_LOCK:
        for runner, _ in _RUNNERS.values():
            runner.close()
        _RUNNERS.clear()


def _worker_runner(source: FmuSource) -> tuple[FmuRunner, threading.Lock]:
    """This process's runner for ``source`` (extracted on first use, removed at process exit)."""

    def path() -> str:
        if source.content is not None and (source.path is None or not Path(source.path).is_file()):
            folder = Path(tempfile.mkdtemp(prefix="dp-sweep-"))
            written = folder / f"{source.key}.fmu"
            written.write_bytes(source.content)
            return str(written)
        return str(source.path)

    return process_runner(source.key, path)


@dataclass(frozen=True)
class SweepChunk:
    """A worker's share: the indices and start values of its cases and the run options."""

    indices: tuple[int, ...]
    cases: tuple[Mapping[str, Any], ...]
    options: Mapping[str, Any]
    reduce: Callable[[np.ndarray], Any] | None = None


def _run_chunk(work: SweepChunk, source: FmuSource) -> list[Any]:
    """Worker: run the chunk's cases one after another with this process's runner."""
    runner, lock = _worker_runner(source)
    out = []
    for index, case in zip(work.indices, work.cases):
        try:
            with lock:
                result = runner.simulate(dict(case), **work.options)
        except FmuRunError as error:
            raise FmuRunError(f"sweep case {index} {dict(case)}: {error}", error.partial_result) from error
        out.append(work.reduce(result) if work.reduce is not None else result)
    return out


def _run_with_runner(task: tuple[Callable[..., Any], Any], source: FmuSource) -> Any:
    """Worker: ``func(runner, item)`` with this process's runner for ``source``."""
    func, item = task
    runner, lock = _worker_runner(source)
    with lock:
        return func(runner, item)


def runner_map(
    func: Callable[[FmuRunner, Any], Any],
    items: Sequence[Any],
    runner: FmuRunner,
    *,
    max_workers: int | None = None,
    label: str = "runs",
    progress: bool | None = None,
    costs: Sequence[float] | None = None,
    unit: str = "run",
) -> list[Any]:
    """``[func(runner, item) for item in items]`` on local worker processes, each with its own runner.

    ``func`` must be a module-level function; with one worker (``max_workers=1`` or a single core)
    it runs here with ``runner``. ``costs`` (estimated run times, any unit) make the workers start
    with the most expensive items, so none is left running alone at the end; results are returned
    in item order either way. A progress bar counts the items.
    """
    workers = min(default_workers() if max_workers is None else max_workers, max(len(items), 1))
    if workers <= 1:
        out = []
        with progress_bar(len(items), label, enabled=progress, unit=unit) as bar:
            for item in items:
                out.append(func(runner, item))
                bar.update(1)
        return out
    order = sorted(range(len(items)), key=lambda i: -costs[i]) if costs is not None else list(range(len(items)))
    source = FmuSource.from_path(runner.fmu_path, embed=False)
    results, _ = parallel_map(_run_with_runner, [(func, items[i]) for i in order], shared=source,
                              max_workers=workers, progress=progress, label=label, unit=unit)
    out: list[Any] = [None] * len(items)
    for i, result in zip(order, results):
        out[i] = result
    return out


def timed_simulate(runner: FmuRunner, item: tuple[Mapping[str, Any], Mapping[str, Any]]) -> tuple[np.ndarray, float]:
    """Worker for :func:`runner_map`: ``runner.simulate(start_values, **options)`` for ``item = (start_values,
    options)``, and the run's CPU time [s] (this process's)."""
    import time

    start_values, options = item
    t0 = time.process_time()
    result = runner.simulate(dict(start_values), **options)
    return result, time.process_time() - t0


def run_sweep(
    fmu_path: str | Path,
    cases: Sequence[Mapping[str, Any]],
    *,
    stop_time: float = 10.0,
    output_interval: float = 0.01,
    outputs: Sequence[str] | None = None,
    reduce: Callable[[np.ndarray], Any] | None = None,
    max_workers: int | None = None,
    scheduler: Any = None,
    progress: bool | None = None,
) -> list[Any]:
    """Run the FMU for every case (start values by name); results in case order.

    Each result is fmpy's structured array (``time`` and ``outputs``), or ``reduce(result)`` if
    given (computed on the worker, so only the reduced value travels back; it must be a
    module-level function). Parallelism as in :func:`parallel_map`; a failing case raises
    :class:`~double_pendulum.fmu.running.runner.FmuRunError` naming the case.
    """
    options: dict[str, Any] = {"stop_time": stop_time, "output_interval": output_interval}
    if outputs is not None:
        options["outputs"] = tuple(outputs)
    indexed = list(enumerate(cases))
    serial = max_workers == 1 and scheduler is None
    parts = chunk(indexed, 1 if serial else CHUNKS_PER_WORKER * (max_workers or default_workers()))
    work = [SweepChunk(tuple(i for i, _ in part), tuple(dict(c) for _, c in part), options, reduce) for part in parts]
    source = FmuSource.from_path(fmu_path, embed=scheduler is not None)
    results, _ = parallel_map(
        _run_chunk,
        work,
        shared=source,
        max_workers=max_workers,
        scheduler=scheduler,
        progress=progress,
        label=f"sweep ({len(cases)} runs)",
        weights=[len(w.indices) for w in work],
    )
    return list(itertools.chain.from_iterable(results))


# ---------------------------------------------------------------------------- case generators
def grid_cases(base: Mapping[str, Any] | None = None, **axes: Sequence[Any]) -> list[dict[str, Any]]:
    """Full factorial cases: every combination of the ``axes`` values (last axis fastest) on ``base``."""
    names = list(axes)
    return [{**(base or {}), **dict(zip(names, combo))} for combo in itertools.product(*axes.values())]


def random_cases(
    n: int,
    *,
    seed: int,
    base: Mapping[str, Any] | None = None,
    uniform: Mapping[str, tuple[float, float]] | None = None,
    normal: Mapping[str, tuple[float, float]] | None = None,
) -> list[dict[str, Any]]:
    """``n`` cases drawn from ``numpy.random.default_rng(seed)``: same seed, same cases.

    ``uniform`` maps a name to ``(low, high)``, ``normal`` to ``(mean, standard deviation)``;
    names are drawn in sorted order so the result does not depend on the mappings' order.
    """
    rng = np.random.default_rng(seed)
    draws: dict[str, np.ndarray] = {}
    for name in sorted(uniform or {}):
        low, high = (uniform or {})[name]
        draws[name] = rng.uniform(low, high, size=n)
    for name in sorted(normal or {}):
        mean, sd = (normal or {})[name]
        if not (math.isfinite(sd) and sd >= 0):
            raise ValueError(f"invalid standard deviation for {name}: {sd!r}")
        draws[name] = rng.normal(mean, sd, size=n)
    return [{**(base or {}), **{k: float(v[i]) for k, v in draws.items()}} for i in range(n)]


def where_runs(n_items: int, max_workers: int | None = None) -> str:
    """Where ``n_items`` items of a sweep with ``max_workers`` (None: :func:`default_workers`) run, for a step line:
    "in this process" or "on N worker processes"."""
    n = min(n_items, default_workers() if max_workers is None else max_workers)
    return "in this process" if n <= 1 else f"on {n} worker processes"
