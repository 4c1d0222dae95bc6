"""The project's data, shipped inside the package as ``double_pendulum.data``.

``seed_table1.csv`` is the seed report's measured track (Table 1), ``reference/`` holds
reference trajectories and ``reference/fmu/`` the FMUs' reference results; see ``README.md`` beside
this file. The ``.py`` scripts here regenerate
them and are not imported by the package.
"""

from importlib.resources import files
from pathlib import Path


def data_path(name: str) -> Path:
    """Return the path of the shipped data file ``name`` (e.g. ``"seed_table1.csv"``)."""
    return Path(str(files(__name__) / name))
