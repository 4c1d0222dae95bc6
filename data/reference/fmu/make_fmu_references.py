"""Generate the committed reference results of the FMUs in ``data/reference/fmu/``.

For every reference case (``double_pendulum.fmu.crosscheck.reference_cases``: the FMI 2.0 and FMI 3.0 FMUs,
Co-Simulation and Model Exchange, the container) this builds the FMUs afresh, runs each case in fmpy at tight tolerance
(the FMU's own integrator at rtol 1e-12, atol 1e-14; under Model Exchange fmpy's CVode at 1e-12) and writes

    <fmi_version>/<fmi_type>/<Model>/<Model>_ref.csv   the reference result (time first, at most 10 outputs)
    <fmi_version>/<fmi_type>/<Model>/<Model>_in.csv    the inputs (every input of the FMU)
    <fmi_version>/<fmi_type>/<Model>/<Model>_ref.opt   StartTime, StopTime, StepSize, RelTol
    references.json                                    what produced each: FMU, start values, solver, versions

in the FMI Cross-Check's formats; ``double-pendulum cross-check DIR`` puts them beside the FMUs, and
``tests/test_reference_results.py`` checks that freshly built FMUs reproduce them in fmpy and in the C host.

Usage: ``python data/reference/fmu/make_fmu_references.py`` (with the package installed).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

from double_pendulum.fmu.crosscheck.reference_runs import build_case_fmus, write_references

HERE = Path(__file__).resolve().parent


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="dp_references_") as tmp:
        record = write_references(HERE, build_case_fmus(tmp))
    for folder in record["cases"]:
        print(f"wrote {HERE / folder}")
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    os._exit(code)  # pythonfmu can abort the interpreter's teardown after its FMUs ran (NTNU-IHB/PythonFMU#228)
