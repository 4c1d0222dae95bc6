"""Write the README's picture: one frame of a default run's measured_vs_sim animation.

    python scripts/readme_picture.py RESULTS [--at 4.0]

Takes the frame of RESULTS/measured_vs_sim/measured_vs_sim.gif shown at --at seconds after its start (the GIF plays
in real time, so its frames' durations add up to the time) and writes it to docs/images/measured_vs_sim.png. Run
it after ``double-pendulum run measured_vs_sim`` (default mode) when the animation or the prediction changes.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from PIL import Image

REPO = Path(__file__).resolve().parents[1]
TARGET = REPO / "docs" / "images" / "measured_vs_sim.png"


def frame_at(gif: Path, seconds: float) -> Image.Image:
    """The frame of ``gif`` on screen ``seconds`` after it starts."""
    with Image.open(gif) as image:
        shown_ms = 0
        for k in range(image.n_frames):
            image.seek(k)
            shown_ms += image.info["duration"]
            if shown_ms > 1000 * seconds:
                break
        return image.convert("RGB")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--at", type=float, default=4.0, help="seconds after the animation's start (default: 4)")
    args = parser.parse_args(argv)
    folder = args.results / "measured_vs_sim"
    if json.loads((folder / "summary.json").read_text()).get("quick"):
        print("measured_vs_sim: a quick run, not the default one: no picture written", file=sys.stderr)
        return 1
    TARGET.parent.mkdir(parents=True, exist_ok=True)
    frame_at(folder / "measured_vs_sim.gif", args.at).save(TARGET, optimize=True)
    print(f"wrote {TARGET.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
