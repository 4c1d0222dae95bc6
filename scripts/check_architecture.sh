#!/usr/bin/env bash
# Check the import contracts in .importlinter (import-linter) on the package as it ships, and the C loader's
# layers (scripts/check_loader_layers.py).
#
# The repository's scenarios/, fmu_src/ and data/ are mapped into double_pendulum by
# pyproject.toml; an editable install resolves them through an import hook that import-linter's
# file walk cannot see. So this builds the wheel, unpacks it and lints that tree.
# Usage: scripts/check_architecture.sh [PYTHON]   (PYTHON: an interpreter with import-linter and pip)
set -euo pipefail
cd "$(dirname "$0")/.."
python=${1:-.venv/bin/python}
python="$(cd "$(dirname "$python")" && pwd)/$(basename "$python")"
# The C loader's units: layered, no circle (as import-linter below for the Python side).
"$python" scripts/check_loader_layers.py >/dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# setuptools reuses build/lib and keeps files deleted since: build from a clean scratch folder
rm -rf build/lib build/bdist.*
"$python" -m pip wheel -q --no-deps -w "$tmp/wheel" . >/dev/null
"$python" -m zipfile -e "$tmp"/wheel/*.whl "$tmp/tree"
cp .importlinter "$tmp/tree/"
cd "$tmp/tree" && PYTHONPATH="$tmp/tree" "$(dirname "$python")/lint-imports" --no-cache
