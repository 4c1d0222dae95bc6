"""``run --track FILE.csv --pendulum FILE.toml``: a user's own camera track through the scenarios that analyse one
(:data:`TRACK_SCENARIOS`), read and checked (:mod:`double_pendulum.analysis.track.user_track`) before anything is
written."""

from __future__ import annotations

import argparse
from typing import Any

from .common import CliError

TRACK_SCENARIOS: tuple[str, ...] = ("energy_decay", "loss_identification", "measured_vs_sim")
"""The scenarios that analyse a camera track and take a user's (``--track``)."""


def add_track_options(parser: argparse.ArgumentParser) -> None:
    """``--track``, ``--pendulum``, ``--columns``, ``--scale``, ``--fps``."""
    group = parser.add_argument_group(
        "your own record", "analyse your own camera track instead of the seed's (energy_decay, loss_identification, "
        "measured_vs_sim; see docs/data-analysis.md, 'Analyse your own pendulum')")
    group.add_argument("--track", metavar="FILE.csv", help="your track: a CSV file with the time and both bobs' x, y "
                       "(columns t_s, x1_m, y1_m, x2_m, y2_m unless --columns names others)")
    group.add_argument("--pendulum", metavar="FILE.toml", help="your pendulum (needed with --track): m1, m2 [kg]; "
                       "l1, l2 [m] where known (else fitted from the track); rods m_rod1, m_rod2 [kg], L_rod1, "
                       "L_rod2 [m] if any")
    group.add_argument("--columns", metavar="Q=NAME,...", help="your columns for t, x1, y1, x2, y2, e.g. "
                       "t=time,x1=xA,y1=yA,x2=xB,y2=yB (a number is a column's position, 1 the first)")
    group.add_argument("--scale", type=float, default=1.0, metavar="M_PER_UNIT",
                       help="metres per unit of the positions (0.01 for cm; default 1: metres)")
    group.add_argument("--fps", type=float, default=None, help="the camera's frame rate [1/s] (default: from the "
                       "times); give it when the times are rounded")


def read_record(args: argparse.Namespace, names: tuple[str, ...]) -> Any:
    """The user's record of ``--track`` (None without it), after checking the options and the scenarios ``names``:
    a :class:`~double_pendulum.analysis.track.user_track.UserRecord`, or a :class:`CliError` of one line."""
    if args.track is None:
        extra = [f"--{k}" for k in ("pendulum", "columns", "fps") if getattr(args, k) is not None]
        if args.scale != 1.0:
            extra.append("--scale")
        if extra:
            raise CliError(f"{', '.join(extra)} describe(s) your own track: give it with --track FILE.csv")
        return None
    if "all" in args.scenarios:
        raise CliError(f"--track: 'all' runs every scenario; the ones that analyse a camera track: "
                       f"{', '.join(TRACK_SCENARIOS)}")
    for name in names:
        if name not in TRACK_SCENARIOS:
            raise CliError(f"--track: {name} does not analyse a camera track; the scenarios that do: "
                           f"{', '.join(TRACK_SCENARIOS)}")
    if args.pendulum is None:
        raise CliError("--track needs --pendulum FILE.toml with the masses m1, m2 [kg]: a camera track does not "
                       "weigh the bobs")
    from ..analysis.track import user_track  # noqa: PLC0415 - NumPy takes a while to import

    try:
        return user_track.read_record(args.track, args.pendulum, columns=args.columns, scale=args.scale, fps=args.fps)
    except user_track.TrackFileError as error:
        raise CliError(str(error)) from None


def record_line(record: Any) -> str:
    """What the run says of the record before it starts."""
    d = record.track.describe()
    missing = (f"; {d['frames_missing_in_file']} frame(s) without a bob's position (empty cells, NaN or missing rows) "
               "kept as flagged frames, left out of every fit" if d["frames_missing_in_file"] else "")
    jumps = f"; {d['frames_flagged']} frame(s) flagged as tracker jumps" if d["frames_flagged"] else ""
    return (f"your record: {d['file']}, {d['frames']} frames over {d['duration_s']:.2f} s at {d['fps']:.4g} fps "
            f"({d['frame_interval_from']}), pendulum {record.pendulum.path.name}{missing}{jumps}")


def track_flags(args: argparse.Namespace) -> list[str]:
    """The record's options as the page's command line shows them."""
    if args.track is None:
        return []
    flags = ["--track", args.track, "--pendulum", args.pendulum]
    if args.columns:
        flags += ["--columns", args.columns]
    if args.scale != 1.0:
        flags += ["--scale", f"{args.scale:g}"]
    if args.fps is not None:
        flags += ["--fps", f"{args.fps:g}"]
    return flags
