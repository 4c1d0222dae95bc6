#!/usr/bin/env bash
# Install the built wheel (not the source tree) into a fresh virtual environment and run every
# scenario from an unrelated folder: proves that scenarios, adapters and data ship inside the
# double_pendulum distribution and that nothing depends on the repository's layout.
# Usage: scripts/check_wheel.sh [PYTHON] [--full]   (PYTHON: an interpreter with pip; default python3)
set -euo pipefail
cd "$(dirname "$0")/.."
python=${1:-python3}
mode=--quick
[ "${2:-}" = "--full" ] && mode=
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# setuptools reuses build/lib and keeps files deleted since: build from a clean scratch folder
rm -rf build/lib build/bdist.*
"$python" -m pip wheel -q --no-deps -w "$tmp/wheel" . >/dev/null
"$python" -m venv "$tmp/venv"
"$tmp/venv/bin/pip" install -q "$tmp"/wheel/*.whl
cd "$tmp"
"$tmp/venv/bin/double-pendulum" --version
MPLBACKEND=Agg "$tmp/venv/bin/double-pendulum" run all $mode --out "$tmp/results" --build-dir "$tmp"
test -s "$tmp/results/index.html"  # the run's page, from the installed package
echo "wheel install: every scenario ran from $(find "$tmp/results" -mindepth 1 -maxdepth 1 -type d | wc -l) result" \
     "folders, and the run's page is there"
