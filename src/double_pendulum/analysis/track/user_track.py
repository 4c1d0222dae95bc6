r"""A user's own record: their camera track (CSV) and their pendulum (TOML), checked and read into a :class:`Track`.

**The track file** is a CSV file with a header row: the time and both bobs' x and y, y pointing up (the angles
are measured from the downward vertical). By default the seed table's names
(:data:`DEFAULT_COLUMNS`: ``t_s, x1_m, y1_m, x2_m, y2_m``; a ``frame`` column may be there and is not needed), or
the user's names given as ``t=time,x1=xA,y1=yA,x2=xB,y2=yB`` (:func:`parse_columns`), where a whole number is a
column's position (1 = the first), for a file whose names repeat (Tracker's ``t,x,y,x,y``). Rows above the header
(Tracker writes the names of its point masses there) are skipped: the header is the row just above the first row
of numbers. Positions in metres, or in another unit times ``scale`` (0.01 for cm, 0.001 for mm). Empty cells and
``NaN`` are a frame where the tracker lost a bob: such frames stay in the record as flagged frames (every fit
skips them, like a tracker jump of :func:`~.measurement.flag_bad_frames`), at most :data:`MAX_MISSING_FRACTION` of
them.

**The frame interval** dt [s]: every step of the times must be their median step or a whole multiple of it (a
missing row) within :data:`TIME_TOLERANCE` of it; dt is the slope of a straight line through the times over the
frame numbers so counted (times printed to 4 decimals give dt to about 1e-7 s over 600 frames). Given the camera's
rate (``fps``), dt = 1/fps and the times need only agree with it to half a frame (times printed with two decimals at
29.97 fps step by 0.03 and 0.04 s), with n = round((t - t_0)/dt). The record's time is t_0 + n dt.

**The checks** (each a :class:`TrackFileError`, one line, naming the file and the numbers): the columns exist; the
cells are numbers; the time increases; the steps are even; at least :data:`MIN_FRAMES` frames over
:data:`MIN_DURATION_S` (the decay fit's error budget cuts 1.5 s from either end and fits four windows of the
record, the loss fits start from a state fitted to 10 frames after the release); each bob stays at a near-constant
distance: the robust scatter (1.4826 MAD) of the upper bob's distance from the fitted pivot and of the distance
between the bobs at most :data:`MAX_LENGTH_SPREAD` of that distance (rigid rods: the seed's record 0.2 % and 2 %);
at most :data:`MAX_FLAGGED_FRACTION` of the frames flagged; the upper bob below the pivot in most frames (else y
points down, as in image coordinates).

**The pendulum file** (TOML, :func:`read_pendulum`) holds the fields of
:class:`~double_pendulum.model.parameters.PendulumParameters` that are known: the masses ``m1``, ``m2`` [kg] are
required (a track does not weigh the bobs), ``l1``, ``l2`` [m] are taken from the track (circle fit, with their
errors) where not given, ``g`` [m/s^2] and the rods ``m_rod1``, ``m_rod2`` [kg], ``L_rod1``, ``L_rod2`` [m]
(default: point masses on massless rods) are optional.
"""

from __future__ import annotations

import csv
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ...model.parameters import ParameterError, PendulumParameters
from .measurement import Geometry, Reconstruction, Track, fit_geometry, flag_bad_frames, reconstruct, robust_sigma
from .tilt import RecordGeometry, record_geometry

DEFAULT_COLUMNS: dict[str, str] = {"t": "t_s", "x1": "x1_m", "y1": "y1_m", "x2": "x2_m", "y2": "y2_m"}
"""The quantities of a track and their columns in the seed's table (``data/seed_table1.csv``)."""
MIN_FRAMES = 100
"""Fewest frames a record may have (see :data:`MIN_DURATION_S`)."""
MIN_DURATION_S = 8.0
"""Shortest record [s]: the error budget of b leaves 1.5 s out at either end and fits b in four windows of the
record, a slow swing of a 30 cm pendulum takes about 1.3 s."""
TIME_TOLERANCE = 0.1
"""How far [dt] a time step may be from dt or a whole multiple of it (without ``fps``)."""
MAX_MISSING_FRACTION = 0.1
"""Largest share of frames without both bobs' positions (empty or NaN cells, missing rows)."""
MAX_FLAGGED_FRACTION = 0.2
"""Largest share of frames flagged as tracker jumps or missing."""
MAX_LENGTH_SPREAD = 0.05
"""Largest robust scatter of a rod's length from frame to frame, relative to the length."""
MAX_LENGTH_MISMATCH = 0.2
"""Largest relative difference between a length the pendulum file gives and the track's (the markers may sit off
the bobs' centres of mass, by far less than this)."""
PENDULUM_FIELDS = ("m1", "m2", "l1", "l2", "g", "m_rod1", "m_rod2", "L_rod1", "L_rod2")
"""The keys a pendulum file may hold (fields of :class:`PendulumParameters`); ``m1``, ``m2`` required."""


class TrackFileError(ValueError):
    """A user's track or pendulum file that cannot be analysed: the message is one line naming the file."""


def parse_columns(text: str | None) -> dict[str, str | int]:
    """The column of each quantity from ``"t=time,x1=xA,..."`` (only those that differ from :data:`DEFAULT_COLUMNS`
    need be given); a whole number is a column's position, 1 for the first. None or "": the defaults."""
    columns: dict[str, str | int] = dict(DEFAULT_COLUMNS)
    for item in (text or "").split(","):
        if not item.strip():
            continue
        key, sep, name = (part.strip() for part in item.partition("="))
        if not sep or key not in DEFAULT_COLUMNS or not name:
            raise TrackFileError(f"--columns {text!r}: each item is QUANTITY=COLUMN with QUANTITY one of "
                                 f"{', '.join(DEFAULT_COLUMNS)} (e.g. t=time,x1=xA), got {item.strip()!r}")
        columns[key] = int(name) if name.isdigit() else name
    return columns


@dataclass(frozen=True, eq=False)
class UserTrack:
    """A user's track read by :func:`read_track`: the :class:`Track` (positions in m, frame interval ``track.dt``),
    the file, where its frame interval came from, the frames missing in the file and flagged as jumps, the columns
    read and the scale applied."""

    track: Track
    path: Path
    dt_from: str
    n_missing: int
    n_flagged: int
    columns: dict[str, str]
    scale: float

    @property
    def name(self) -> str:
        return self.path.name

    def describe(self) -> dict[str, Any]:
        """The record as the summaries state it."""
        return {"file": self.name, "frames": len(self.track), "duration_s": float(self.track.t[-1] - self.track.t[0]),
                "frame_interval_s": self.track.dt, "fps": 1.0 / self.track.dt, "frame_interval_from": self.dt_from,
                "frames_missing_in_file": self.n_missing, "frames_flagged": self.n_flagged,
                "columns": self.columns, "scale_to_m": self.scale}  # fmt: skip


def _numbers(row: list[str], index: list[int]) -> list[float] | None:
    """The cells ``index`` of ``row`` as numbers (empty: NaN), or None if one is not a number."""
    out = []
    for i in index:
        cell = row[i].strip() if i < len(row) else ""
        if not cell:
            out.append(math.nan)
            continue
        try:
            out.append(float(cell))
        except ValueError:
            return None
    return out


def _read_table(path: Path, columns: Mapping[str, str | int]) -> tuple[dict[str, str], np.ndarray, int]:
    """The columns' names, the numbers (rows x t, x1, y1, x2, y2) and the line of the first data row."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as fh:
            rows = [r for r in csv.reader(fh) if any(c.strip() for c in r)]
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise TrackFileError(f"{path}: cannot be read as a CSV file ({error})") from None
    numeric = [all(_is_number(c) for c in r if c.strip()) and sum(1 for c in r if c.strip()) >= 3 for r in rows]
    first = next((i for i, n in enumerate(numeric) if n), None)
    if first is None or first == 0:
        text = "".join("".join(r) for r in rows[:5])
        other = next((name for sep, name in ((";", "semicolons"), ("\t", "tabs")) if sep in text), None)
        raise TrackFileError(f"{path}: " + (f"its columns are separated by {other}; export with commas (and a decimal "
                                            "point)" if other else "needs a header row of column names above rows of "
                                            "numbers, separated by commas"))
    header = [h.strip() for h in rows[first - 1]]
    index, names = [], {}
    for key, col in columns.items():
        if isinstance(col, int):
            if not 1 <= col <= len(header):
                raise TrackFileError(f"{path}: column {col} for {key} does not exist (the file has {len(header)} "
                                     f"columns: {', '.join(header)})")
            index.append(col - 1)
        elif header.count(col) == 1:
            index.append(header.index(col))
        else:
            missing = "appears more than once (give its position, e.g. x1=2)" if col in header else "is missing"
            raise TrackFileError(f"{path}: column {col!r} ({key}) {missing}; columns present: {', '.join(header)}; "
                                 "name yours with --columns t=...,x1=...,y1=...,x2=...,y2=...")
        names[key] = header[index[-1]]
    data = []
    for line, row in enumerate(rows[first:], start=first + 1):
        values = _numbers(row, index)
        if values is None:
            key, i = next((k, i) for k, i in zip(names, index) if not _is_number(row[i] if i < len(row) else ""))
            raise TrackFileError(f"{path}: row {line}: {names[key]} = {row[i]!r} is not a number (decimal point, "
                                 "comma between columns)")
        data.append(values)
    return names, np.array(data, dtype=float).reshape(-1, 5), first + 1


def _is_number(cell: str) -> bool:
    cell = cell.strip()
    if not cell:
        return True
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _frame_numbers(path: Path, t: np.ndarray, first_line: int, fps: float | None) -> tuple[np.ndarray, float, str]:
    """Frame numbers n >= 0 of the rows, the frame interval [s] and where it came from (module docstring)."""
    if len(t) < 2:
        raise TrackFileError(f"{path}: {len(t)} frame(s); at least {MIN_FRAMES} over {MIN_DURATION_S:g} s are needed")
    step = np.diff(t)
    bad = np.flatnonzero(~(step > 0))
    if len(bad):
        i = int(bad[0])
        raise TrackFileError(f"{path}: the time does not increase at row {first_line + i + 1} "
                             f"(t = {t[i + 1]:g} s after {t[i]:g} s)")
    if fps is not None:
        dt, source = 1.0 / fps, f"given: {fps:g} fps"
        n = np.rint((t - t[0]) / dt)
        off = np.abs(t - t[0] - n * dt) / dt
        if np.max(off) > 0.5 or np.any(np.diff(n) < 1):
            i = int(np.argmax(off))
            raise TrackFileError(f"{path}: the times do not fit {fps:g} fps: row {first_line + i} (t = {t[i]:g} s) is "
                                 f"{off[i]:.2f} frames off the grid; is the rate right?")
    else:
        median = float(np.median(step))
        k = step / median
        if np.max(np.abs(k - np.rint(k))) > TIME_TOLERANCE or np.min(np.rint(k)) < 1:
            raise TrackFileError(f"{path}: the time steps are uneven: {np.min(step):.4g} to {np.max(step):.4g} s "
                                 f"(median {median:.4g} s); times cut to a few decimals? give the camera's rate with "
                                 "--fps (e.g. --fps 30)")
        n = np.concatenate([[0.0], np.cumsum(np.rint(k))])
        dt = float(np.polyfit(n, t, 1)[0])  # the slope of t over the frame number: the rounding of the times averages
        source = "fitted to the times"
    return n.astype(int), dt, source


def read_track(path: str | Path, *, columns: Mapping[str, str | int] | None = None, scale: float = 1.0,
               fps: float | None = None) -> UserTrack:  # fmt: skip
    """Read and check a user's track file (module docstring); positions times ``scale`` [m per unit]."""
    path = Path(path)
    if not path.is_file():
        raise TrackFileError(f"{path}: no such file")
    if not (math.isfinite(scale) and scale > 0):
        raise TrackFileError(f"--scale = {scale!r}: must be a positive number (metres per unit of the file)")
    if fps is not None and not (math.isfinite(fps) and fps > 0):
        raise TrackFileError(f"--fps = {fps!r}: must be a positive number (frames per second)")
    names, data, first_line = _read_table(path, {**DEFAULT_COLUMNS, **dict(columns or {})})
    t = data[:, 0]
    if np.any(~np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise TrackFileError(f"{path}: row {first_line + i}: the time ({names['t']}) is empty")
    n, dt, source = _frame_numbers(path, t, first_line, fps)
    frames = int(n[-1]) + 1
    duration = (frames - 1) * dt
    if frames < MIN_FRAMES or duration < MIN_DURATION_S:
        raise TrackFileError(f"{path}: {frames} frames over {duration:.2f} s; at least {MIN_FRAMES} frames over "
                             f"{MIN_DURATION_S:g} s are needed (the decay fit leaves 1.5 s out at either end and fits "
                             "four windows of the record)")
    pos = np.full((frames, 4), np.nan)
    pos[n] = data[:, 1:] * scale
    missing = ~np.all(np.isfinite(pos), axis=1)
    if missing.mean() > MAX_MISSING_FRACTION:
        raise TrackFileError(f"{path}: {int(missing.sum())} of {frames} frames lack a bob's position (empty, NaN or "
                             f"missing rows), more than {MAX_MISSING_FRACTION:.0%}; track the bobs in those frames")
    x1, y1, x2, y2 = (pos[:, k] for k in range(4))
    valid = flag_bad_frames(x1, y1, x2, y2)
    _check_rigid(path, x1, y1, x2, y2, valid)
    flagged = int(np.count_nonzero(~valid & ~missing))
    if (~valid).mean() > MAX_FLAGGED_FRACTION:
        raise TrackFileError(f"{path}: {int(np.count_nonzero(~valid))} of {frames} frames are missing or jump off the "
                             f"circle about the pivot, more than {MAX_FLAGGED_FRACTION:.0%}")
    if missing.any():  # the angles are unwrapped over every frame: missing ones get straight-line positions (flagged)
        idx = np.arange(frames)
        for a in (x1, y1, x2, y2):
            a[missing] = np.interp(idx[missing], idx[~missing], a[~missing])
    frame = np.arange(frames)
    track = Track(frame=frame, t=t[0] + frame * dt, x1=x1, y1=y1, x2=x2, y2=y2, valid=valid, dt=dt)
    return UserTrack(track, path, source, int(missing.sum()), flagged, names, scale)


def _check_rigid(path: Path, x1: np.ndarray, y1: np.ndarray, x2: np.ndarray, y2: np.ndarray,
                 valid: np.ndarray) -> None:  # fmt: skip
    """Raise if the upper bob is above the pivot in most frames (y down) or a bob's distance (from the fitted pivot,
    from the other bob) scatters beyond :data:`MAX_LENGTH_SPREAD` (module docstring)."""
    finite = np.isfinite(x1) & np.isfinite(y1) & np.isfinite(x2) & np.isfinite(y2)
    use = valid if valid.sum() >= 4 else finite
    geo = fit_geometry(Track(np.arange(len(x1)), np.arange(len(x1)), x1, y1, x2, y2, use))
    r1 = np.hypot(x1[finite] - geo.pivot.xc, y1[finite] - geo.pivot.yc)
    r2 = np.hypot(x2[finite] - x1[finite], y2[finite] - y1[finite])
    above = float(np.mean(y1[finite] > geo.pivot.yc))
    if above > 0.5:
        raise TrackFileError(f"{path}: the upper bob is above the fitted pivot in {above:.0%} of the frames: y points "
                             "down (image coordinates?); give y pointing up (Tracker's default axes) or negate y1 "
                             "and y2")
    for what, r in (("the upper bob's distance from the fitted pivot", r1), ("the distance between the bobs", r2)):
        median, spread = float(np.median(r)), robust_sigma(r)
        if not spread <= MAX_LENGTH_SPREAD * median:
            raise TrackFileError(f"{path}: {what} scatters by {1e3 * spread:.1f} mm (1.48 MAD) about "
                                 f"{1e3 * median:.1f} mm, {spread / median:.1%}; a rigid rod keeps it within "
                                 f"{MAX_LENGTH_SPREAD:.0%}: are the columns the upper bob (x1, y1) and the lower "
                                 "bob (x2, y2), and the scale right?")


# --- the pendulum file ---------------------------------------------------------------------------


@dataclass(frozen=True)
class UserPendulum:
    """What a user's pendulum file gives: masses [kg], the lengths given [m] (the others are fitted), g and the
    rods, checked as :class:`PendulumParameters` checks them."""

    path: Path
    m1: float
    m2: float
    lengths: dict[str, float] = field(default_factory=dict)
    other: dict[str, float] = field(default_factory=dict)

    @property
    def rods(self) -> dict[str, float]:
        return {k: v for k, v in self.other.items() if k != "g"}

    def describe(self) -> dict[str, Any]:
        return {"file": self.path.name, "m1_kg": self.m1, "m2_kg": self.m2,
                "lengths_given_m": self.lengths, "other_given": self.other}  # fmt: skip


def read_pendulum(path: str | Path) -> UserPendulum:
    """Read and check a pendulum file (module docstring)."""
    path = Path(path)
    if not path.is_file():
        raise TrackFileError(f"{path}: no such file")
    try:
        with path.open("rb") as fh:
            values = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as error:
        raise TrackFileError(f"{path}: not a TOML file ({error})") from None
    unknown = sorted(set(values) - set(PENDULUM_FIELDS))
    if unknown:
        raise TrackFileError(f"{path}: unknown key(s) {', '.join(unknown)}; a pendulum file may give "
                             f"{', '.join(PENDULUM_FIELDS)}")
    absent = [k for k in ("m1", "m2") if k not in values]
    if absent:
        raise TrackFileError(f"{path}: {' and '.join(absent)} [kg] missing: the masses are required (a camera track "
                             "does not weigh the bobs)")
    try:
        PendulumParameters(**{k: (float(v) if isinstance(v, int) and not isinstance(v, bool) else v)
                              for k, v in values.items()})  # the dataclass's checks, with units
    except ParameterError as error:
        raise TrackFileError(f"{path}: {error}") from None
    given = {k: float(v) for k, v in values.items()}
    lengths = {k: given.pop(k) for k in ("l1", "l2") if k in given}
    m1, m2 = given.pop("m1"), given.pop("m2")
    return UserPendulum(path, m1, m2, lengths, given)


# --- the whole record ----------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class UserRecord:
    """A user's track and pendulum, as the scenarios ``energy_decay`` and ``loss_identification`` take it."""

    track: UserTrack
    pendulum: UserPendulum

    @property
    def name(self) -> str:
        """The track file's name, as the results name the record."""
        return self.track.name

    def geometry(self) -> Geometry:
        """Pivot and lengths: fitted from the track (:func:`~.measurement.fit_geometry`), the lengths the pendulum
        file gives put in their place (the pivot stays fitted)."""
        fitted = fit_geometry(self.track.track)
        given = self.pendulum.lengths
        pivot = fitted.pivot._replace(radius=given["l1"]) if "l1" in given else fitted.pivot
        return replace(fitted, pivot=pivot, l2=given.get("l2", fitted.l2))

    def fitted_lengths(self) -> dict[str, float]:
        """l1, l2 [m] fitted from the track and their standard errors (whatever the pendulum file gives)."""
        g = fit_geometry(self.track.track)
        return {"l1": g.l1, "l1_stderr": g.sigma_l1, "l2": g.l2, "l2_stderr": g.sigma_l2}

    @cached_property
    def record_geometry(self) -> RecordGeometry:
        """The record's one geometry (:func:`~.tilt.record_geometry`): :meth:`geometry` and the camera's tilt against
        gravity fitted to the energy of the user's pendulum, with their covariance."""
        p = self.pendulum
        return record_geometry(self.track.track, self.geometry(), m1=p.m1, m2=p.m2, rods=p.rods, g=p.other.get("g"))

    def reconstruction(self, *, tilt: bool = True) -> Reconstruction:
        """The track reconstructed with the user's masses, lengths (:meth:`geometry`), rods and g, turned back by the
        camera's tilt (:attr:`record_geometry`); ``tilt=False``: the untilted track as the camera saw it."""
        p = self.pendulum
        rg = self.record_geometry
        return reconstruct(self.track.track, rg.geometry if tilt else rg.untilted, m1=p.m1, m2=p.m2, rods=p.rods,
                           g=p.other.get("g"))  # fmt: skip

    def describe(self) -> dict[str, Any]:
        """The record and the pendulum as the summaries state them."""
        return {**self.track.describe(), "pendulum": self.pendulum.describe(), "whose": "a user's own record"}


def read_record(track: str | Path, pendulum: str | Path, *, columns: str | None = None, scale: float = 1.0,
                fps: float | None = None) -> UserRecord:  # fmt: skip
    """Read and check a user's track and pendulum file (:func:`read_track`, :func:`read_pendulum`); a length the
    pendulum file gives must be within :data:`MAX_LENGTH_MISMATCH` of the track's (else a unit or a rod is wrong)."""
    record = UserRecord(read_track(track, columns=parse_columns(columns), scale=scale, fps=fps),
                        read_pendulum(pendulum))  # fmt: skip
    fitted = record.fitted_lengths()
    for k, given in record.pendulum.lengths.items():
        if abs(given - fitted[k]) > MAX_LENGTH_MISMATCH * fitted[k]:
            raise TrackFileError(f"{record.pendulum.path}: {k} = {given:g} m, but the track gives {fitted[k]:.4f} m; "
                                 f"they must agree within {MAX_LENGTH_MISMATCH:.0%} (a length in m, the track's "
                                 "scale right?)")
    return record
