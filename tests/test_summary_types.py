"""The typed summaries (``analysis/<study>/summary_types.py``) match the summaries the scenarios write.

Each study's ``summary.json`` is read back by its report through a ``TypedDict``; the project runs no type
checker, so this test holds the types to the data: every scenario's summary from the session's quick run is
checked against its ``TypedDict`` recursively (:func:`mismatches`): every required key present, no key the type
does not declare, and every value of its declared type (a float may be an int, as JSON writes it; ``Any`` is
not looked into). Neither this module nor the ``summary_types`` modules use ``from __future__ import
annotations``: Python 3.11 sees ``NotRequired`` only in annotations evaluated when the class is made.
"""

import types
import typing
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, NotRequired, TypedDict

import pytest
from conftest import quick_scenario

from double_pendulum.analysis.chaos.summary_types import ChaosSummary
from double_pendulum.analysis.coupling.summary_types import CouplingSummary
from double_pendulum.analysis.decay.summary_types import DecaySummary
from double_pendulum.analysis.excitation.summary_types import ExcitationSummary
from double_pendulum.analysis.losses.summary_types import LossesSummary
from double_pendulum.analysis.prediction.summary_types import PredictionSummary
from double_pendulum.analysis.suspension.summary_types import SuspensionSummary

TYPES: dict[str, Any] = {
    "measured_vs_sim": PredictionSummary,
    "loss_identification": LossesSummary,
    "energy_decay": DecaySummary,
    "suspension_transfer": SuspensionSummary,
    "chaos": ChaosSummary,
    "cosimulation": CouplingSummary,
    "base_excitation": ExcitationSummary,
}
"""Each scenario whose report reads its summary, with the summary's type."""


def mismatches(value: Any, hint: Any, path: str = "summary") -> Iterator[str]:
    """Where ``value`` (a summary as read from JSON) departs from the type ``hint``: one line a mismatch."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is Any:
        return
    if typing.is_typeddict(hint):
        if not isinstance(value, dict):
            yield f"{path}: {type(value).__name__}, not a {hint.__name__}"
            return
        fields = typing.get_type_hints(hint)
        for key in sorted(hint.__required_keys__ - value.keys()):
            yield f"{path}: {hint.__name__}'s key {key!r} missing"
        for key in sorted(value.keys() - fields.keys()):
            yield f"{path}: key {key!r} not in {hint.__name__}"
        for key in value.keys() & fields.keys():
            yield from mismatches(value[key], fields[key], f"{path}.{key}")
    elif origin in (typing.Union, types.UnionType):
        found = [list(mismatches(value, arg, path)) for arg in args]
        if all(found):
            yield min(found, key=len)[0] if len(args) == 1 else f"{path}: {value!r:.60} is none of {hint}"
    elif origin is typing.Literal:
        if value not in args:
            yield f"{path}: {value!r} not one of {args}"
    elif origin in (dict, Mapping):
        if not isinstance(value, dict):
            yield f"{path}: {type(value).__name__}, not a dict"
            return
        for key, item in value.items():
            yield from mismatches(item, args[1], f"{path}[{key!r}]")
    elif origin in (list, Sequence, tuple):
        if not isinstance(value, list):
            yield f"{path}: {type(value).__name__}, not a list"
            return
        if origin is tuple and args and args[-1] is not Ellipsis:
            if len(args) != len(value):
                yield f"{path}: {len(value)} items, not {len(args)}"
                return
            for i, (item, arg) in enumerate(zip(value, args, strict=True)):
                yield from mismatches(item, arg, f"{path}[{i}]")
            return
        for i, item in enumerate(value):
            yield from mismatches(item, args[0], f"{path}[{i}]")
    elif hint is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            yield f"{path}: {value!r:.60} is no number"
    elif hint in (int, str, bool):
        if not isinstance(value, hint) or (hint is int and isinstance(value, bool)):
            yield f"{path}: {value!r:.60} is no {hint.__name__}"
    elif hint is type(None) or hint is None:
        if value is not None:
            yield f"{path}: {value!r:.60} is not null"
    else:
        raise TypeError(f"{path}: no check for the type {hint!r}")


@pytest.mark.parametrize("scenario", sorted(TYPES))
def test_each_summary_has_exactly_the_keys_and_types_its_typed_dict_declares(quick_results: Path, scenario: str):
    _, summary = quick_scenario(quick_results, scenario)
    assert list(mismatches(summary, TYPES[scenario])) == []


class _Inner(TypedDict):
    value: float
    unit: str
    note: NotRequired[str]


class _Outer(TypedDict):
    quick: bool
    n: int
    horizon_s: float | None
    inner: _Inner
    by_model: dict[str, _Inner]
    range_s: list[float]


def test_the_check_finds_a_misspelt_key_a_missing_one_and_a_wrong_type():
    good = {"quick": True, "n": 3, "horizon_s": None, "inner": {"value": 1, "unit": "s"},
            "by_model": {"air": {"value": 0.5, "unit": "m", "note": "x"}}, "range_s": [0.0, 2.5]}
    assert list(mismatches(good, _Outer)) == []
    bad = {**good, "horizon": 1.0, "n": True, "inner": {"value": "1", "unit": "s"},
           "by_model": {"air": {"valeu": 0.5, "unit": "m"}}, "range_s": [0.0, None]}
    del bad["horizon_s"]
    assert sorted(mismatches(bad, _Outer)) == [
        "summary.by_model['air']: _Inner's key 'value' missing",
        "summary.by_model['air']: key 'valeu' not in _Inner",
        "summary.inner.value: '1' is no number",
        "summary.n: True is no int",
        "summary.range_s[1]: None is no number",
        "summary: _Outer's key 'horizon_s' missing",
        "summary: key 'horizon' not in _Outer",
    ]
