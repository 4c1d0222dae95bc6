"""The on-disk cache of slow results: computed once, read back unchanged, recomputed when damaged."""

from __future__ import annotations

import numpy as np
import pytest

from double_pendulum.runs import result_cache


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv(result_cache.CACHE_ENV, str(tmp_path))
    return tmp_path


def test_a_result_is_computed_once_and_read_back_unchanged(cache):
    calls = []

    def compute():
        calls.append(1)
        return {"theta": np.array([2.17, 1.1e-3]), "stop": "converged"}

    first = result_cache.cached("fits", {"model": "air+drag"}, compute)
    second = result_cache.cached("fits", {"model": "air+drag"}, compute)
    assert len(calls) == 1
    assert second["stop"] == "converged" and np.array_equal(second["theta"], first["theta"])
    result_cache.cached("fits", {"model": "air"}, compute)  # another key: computed
    assert len(calls) == 2
    assert len(list((cache / "fits").glob("*.pkl"))) == 2
    assert not list((cache / "fits").glob(".*"))  # no partial file left


def test_a_damaged_file_is_computed_anew(cache):
    result_cache.cached("fits", {"k": 1}, lambda: 1)
    (path,) = (cache / "fits").glob("*.pkl")
    path.write_bytes(b"not a pickle")
    assert result_cache.cached("fits", {"k": 1}, lambda: 2) == 2
    assert result_cache.cached("fits", {"k": 1}, lambda: 3) == 2
