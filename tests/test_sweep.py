"""Parameter sweeps of the FMU: local processes, a Dask cluster, determinism, errors, progress."""

from __future__ import annotations

import os

import numpy as np
import pytest

from double_pendulum.analysis.chaos import flips
from double_pendulum.analysis.sweep import (
    chunk,
    grid_cases,
    parallel_map,
    random_cases,
    run_sweep,
    worker_pool,
)
from double_pendulum.fmu.running.runner import FmuRunError
from double_pendulum.runs.workers import WORKERS_ENV, default_workers

OPTIONS = {"stop_time": 0.5, "output_interval": 0.05}


def _cases() -> list[dict]:
    return random_cases(5, seed=3, base={"phi2_0": 0.0}, normal={"phi1_0": (2.0, 0.017)}, uniform={"m2": (0.2, 0.4)})


def _assert_same(a: list[np.ndarray], b: list[np.ndarray]) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert x.dtype.names == y.dtype.names
        for name in x.dtype.names:
            np.testing.assert_array_equal(x[name], y[name])


@pytest.fixture(scope="module")
def serial_results(fmu_path):
    return run_sweep(fmu_path, _cases(), max_workers=1, **OPTIONS)


def test_sweep_on_local_processes_gives_the_direct_runs_in_case_order(fmu_path, runner, serial_results):
    cases = _cases()
    parallel = run_sweep(fmu_path, cases, max_workers=2, **OPTIONS)
    _assert_same(parallel, serial_results)
    _assert_same(serial_results, [runner.simulate(c, **OPTIONS) for c in cases])
    # each case really ran with its own start values
    assert [r["phi1"][0] for r in parallel] == [c["phi1_0"] for c in cases]


def test_sweep_on_a_local_dask_cluster_gives_identical_results(fmu_path, serial_results, tmp_path):
    pytest.importorskip("distributed", reason="dask[distributed] is not installed")
    import dask
    from distributed import LocalCluster

    with dask.config.set({"temporary-directory": str(tmp_path)}), LocalCluster(  # its scratch space, not $TMPDIR
            n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        on_dask = run_sweep(fmu_path, _cases(), scheduler=cluster.scheduler_address, **OPTIONS)
    _assert_same(on_dask, serial_results)


def test_random_cases_are_fixed_by_the_seed():
    a = random_cases(4, seed=7, uniform={"m1": (0.2, 0.4), "l2": (0.1, 0.3)})
    b = random_cases(4, seed=7, uniform={"l2": (0.1, 0.3), "m1": (0.2, 0.4)})  # order of names irrelevant
    c = random_cases(4, seed=8, uniform={"m1": (0.2, 0.4), "l2": (0.1, 0.3)})
    assert a == b and a != c
    assert all(0.2 <= case["m1"] <= 0.4 and 0.1 <= case["l2"] <= 0.3 for case in a)
    with pytest.raises(ValueError, match="standard deviation"):
        random_cases(2, seed=1, normal={"g": (9.81, -1.0)})


def test_grid_cases_and_chunks_keep_the_order():
    cases = grid_cases({"phi2_0": 0.0}, phi1_0=[1.0, 2.0], m2=[0.1, 0.2, 0.3])
    assert [(c["phi1_0"], c["m2"]) for c in cases] == [
        (1.0, 0.1),
        (1.0, 0.2),
        (1.0, 0.3),
        (2.0, 0.1),
        (2.0, 0.2),
        (2.0, 0.3),
    ]
    parts = chunk(list(range(10)), 4)
    assert [len(p) for p in parts] == [3, 3, 2, 2] and sum(parts, []) == list(range(10))


def test_a_failing_case_is_reported_with_its_index_and_the_fmu_message(fmu_path):
    cases = [{"phi1_0": 1.0}, {"l1": -1.0}]
    with pytest.raises(FmuRunError, match=r"sweep case 1 .*l1"):
        run_sweep(fmu_path, cases, max_workers=1, **OPTIONS)


def _final_phi2(result: np.ndarray) -> float:
    return float(result["phi2"][-1])


def test_reduce_returns_only_what_is_asked_for(fmu_path, serial_results):
    reduced = run_sweep(fmu_path, _cases(), max_workers=1, reduce=_final_phi2, **OPTIONS)
    assert reduced == [float(r["phi2"][-1]) for r in serial_results]


def test_batch_work_split_over_processes_is_identical_to_one_batch():
    serial = flips.flip_time_map(16, 16, t_max=1.5, max_workers=1)
    parallel = flips.flip_time_map(16, 16, t_max=1.5, max_workers=2)
    assert parallel.workers == 2
    np.testing.assert_array_equal(parallel.time, serial.time)
    np.testing.assert_array_equal(parallel.rod, serial.rod)


def test_progress_bar_counts_and_estimates(capsys):
    results, _ = parallel_map(abs, [-1, -2, -3, -4], max_workers=1, progress=True, label="sweep")
    assert results == [1, 2, 3, 4]
    shown = capsys.readouterr().err
    assert "sweep" in shown and "4/4" in shown and "100%" in shown and "run/s" in shown
    parallel_map(abs, [-1, -2], max_workers=1, label="sweep")  # stderr is not a terminal: silent by default
    assert capsys.readouterr().err == ""


def test_a_worker_pool_serves_several_maps_with_the_same_processes():
    """parallel_map(pool=...) runs on the pool's workers (no new processes per call), results in item order."""
    with worker_pool(2) as pool:
        assert pool is not None and pool.workers == 2
        first, used = parallel_map(abs, [], pool=pool)  # nothing to do: no worker needed
        assert first == [] and used == 1
        a, used = parallel_map(abs, [-3, -1, -2, -5], pool=pool)
        assert a == [3, 1, 2, 5] and used == 2
        pids1, _ = parallel_map(_pid, list(range(6)), pool=pool)
        pids2, _ = parallel_map(_pid, list(range(6)), pool=pool)
    assert os.getpid() not in pids1 + pids2 and len(set(pids1) | set(pids2)) <= 2  # the same two workers
    with worker_pool(1) as none:
        assert none is None


def _pid(_: int) -> int:
    return os.getpid()


@pytest.mark.parametrize(("value", "expected"), [("1", 1), ("", None), ("0", None), ("-2", None), ("many", None)])
def test_default_workers_are_capped_by_the_environment_variable_when_it_is_a_positive_integer(monkeypatch, value,
                                                                                             expected):  # fmt: skip
    monkeypatch.delenv(WORKERS_ENV, raising=False)
    cores = default_workers()
    monkeypatch.setenv(WORKERS_ENV, value)
    assert default_workers() == (cores if expected is None else min(cores, expected))
    monkeypatch.setenv(WORKERS_ENV, str(cores + 5))
    assert default_workers() == cores  # a cap, never more processes than cores


def test_the_reused_instance_gives_the_numbers_of_a_new_instance_for_every_case(fmu_path):
    """FmuRunner keeps one instance and resets it between runs (fmi2Reset): every case, also one after a
    failed case and one with inputs, bit for bit what a new instance per case gives."""
    from double_pendulum.fmu.running.runner import FmuRunner

    cases = [*_cases(), {"l1": -1.0}, {"phi1_0": 2.5, "air_drag": True}]
    signal = np.array([(0.0, 0.3), (0.5, 0.3)], dtype=[("time", float), ("tau1", float)])

    def all_runs(runner: FmuRunner) -> list:
        out = []
        for case in cases:
            try:
                out.append(runner.simulate(case, **OPTIONS))
            except FmuRunError as error:
                out.append(str(error).split("FMU says: ")[-1])
        out.append(runner.simulate({"phi1_0": 0.3}, input=signal, **OPTIONS))
        return out

    with FmuRunner(fmu_path) as reused, FmuRunner(fmu_path, reuse_instance=False) as fresh:
        assert reused.reuse_instance
        a, b = all_runs(reused), all_runs(fresh)
    assert a[5] == b[5] and "invalid l1 = -1.0 m" in a[5]  # the failed case says why, either way
    _assert_same([r for r in a if not isinstance(r, str)], [r for r in b if not isinstance(r, str)])


MEMORY_SCRIPT = """
import sys
from double_pendulum.analysis.sweep import random_cases
from double_pendulum.fmu.running.runner import FmuRunner

def rss_kib():
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * 4

cases = random_cases(550, seed=5, uniform={"phi1_0": (0.5, 2.5)})
with FmuRunner(sys.argv[1]) as runner:
    for case in cases[:150]:
        runner.simulate(case, stop_time=0.1, output_interval=0.01)
    before = rss_kib()
    for case in cases[150:]:
        runner.simulate(case, stop_time=0.1, output_interval=0.01)
    print(rss_kib() - before)
"""


@pytest.mark.slow
def test_a_long_sweep_in_one_worker_adds_little_memory(fmu_path):
    """400 short cases in a worker of its own, after 150 that warm up imports, caches and the allocator's
    pools: resident memory grows by less than 2 MB (5 MB per 1,000 cases is the bound; before the instance
    was reused and the guard stood in front, 68 MB per 1,000; benchmarks/sweep_cost.py)."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", MEMORY_SCRIPT, str(fmu_path)], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    grown = int(done.stdout.strip().splitlines()[-1])
    assert grown < 2048, f"{grown} KiB over 400 cases"
