#!/usr/bin/env bash
# Memory safety of the FMUs' Linux binaries (the C loader, their one binary), proved two ways:
#  1. AddressSanitizer + UndefinedBehaviorSanitizer (and LeakSanitizer): the FMUs' loader and the C torture
#     hosts built with the sanitizers (DOUBLE_PENDULUM_SANITIZE=1, tests/sanitize.py), then every probe of
#     tests/test_guard.py, its threads and a soak in those hosts, each started with a bare environment.
#  2. valgrind memcheck: a Python host (scripts/memory_host.py) runs the FMI 2 and FMI 3 FMUs (co-simulation
#     and model exchange) with fmpy, does ordinary SciPy work and exits normally, and once more exits with an
#     instance alive; errors whose stack runs through the FMU's binaries can never be suppressed, and the
#     only suppressions (scripts/valgrind-python.supp) are known false positives of CPython and ld.so.
# Any finding fails, with its report printed; each part prints its time.
# Usage: scripts/check_memory.sh PYTHON   (the project's environment's interpreter, e.g. .venv/bin/python)
set -euo pipefail
cd "$(dirname "$0")/.."
python=${1:?usage: scripts/check_memory.sh PYTHON}
work=$(mktemp -d "${TMPDIR:-/tmp}/check-memory.XXXXXX")
trap 'rm -rf "$work"' EXIT
failed=()

now() { date +%s.%N; }
took() { awk -v start="$1" -v end="$(now)" 'BEGIN { printf "%.0f s", end - start }'; }
started=$(now)

# --- 1. ASan + UBSan: the torture hosts' tests, built sanitized -----------------------------------------
# -n0: one process (the module runs on one xdist worker anyway, and starting workers costs more than it saves).
part=$(now)
if ! "$python" -c "from double_pendulum.fmu.build import loader; raise SystemExit(loader.c_compiler() is None)"; then
    echo "memory 1/2 (ASan/UBSan): SKIPPED: no C compiler (\$CC, cc, gcc or clang) to build the loader and hosts"
else
    echo "memory 1/2 (ASan/UBSan): tests/test_guard.py with the loader and the torture hosts built sanitized ..."
    if DOUBLE_PENDULUM_SANITIZE=1 "$python" -m pytest -q -n0 -p no:cacheprovider tests/test_guard.py; then
        echo "memory 1/2 (ASan/UBSan): no finding in any probe, the threads or the soak ($(took "$part"))"
    else
        echo "memory 1/2 (ASan/UBSan): FAILED: a sanitizer report or a failed test above ($(took "$part"))"
        failed+=("ASan/UBSan")
    fi
fi

# --- 2. valgrind: a Python host through fmpy and through exit ---------------------------------------------
# Debian's valgrind, installed here as .ci/run installs chromium: where it is missing and this runs as root.
part=$(now)
if ! command -v valgrind >/dev/null; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        echo "memory 2/2 (valgrind): installing valgrind (apt-get) ..."
        (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind >/dev/null) \
            || echo "memory 2/2 (valgrind): could not install valgrind"
    fi
fi
if ! command -v valgrind >/dev/null; then
    echo "memory 2/2 (valgrind): SKIPPED: no valgrind, and no root with apt-get to install it"
else
    echo "memory 2/2 (valgrind): building the FMUs (plain loader) ..."
    env -u DOUBLE_PENDULUM_LOADER_CFLAGS "$python" -m double_pendulum.cli build -o "$work/build" >"$work/build.log" 2>&1 \
        || { cat "$work/build.log"; echo "memory 2/2 (valgrind): FAILED: the FMUs did not build"; exit 1; }
    # PYTHONMALLOC=malloc: each Python object its own malloc block, which memcheck watches; PYTHONHASHSEED=0:
    # the same code paths every run. fmpy extracts the FMUs into TMPDIR, the alive run into the build folder.
    # Leaks are no errors here (a Python process exits with its objects alive), and their records are not
    # written (the XML would hold them all). 24 callers: deep enough for the ld.so suppression to see CPython's
    # import below its dlopen. The XML names every frame's object file (the text log does not where there is
    # debug info): valgrind_findings.py reads it.
    for mode in simulate alive; do
        step=$(now)
        mkdir -p "$work/tmp-$mode"
        status=0
        TMPDIR="$work/tmp-$mode" PYTHONMALLOC=malloc PYTHONHASHSEED=0 \
            valgrind --num-callers=24 --error-exitcode=99 --errors-for-leak-kinds=none --show-leak-kinds=none \
            --suppressions=scripts/valgrind-python.supp --xml=yes --xml-file="$work/valgrind-$mode.xml" \
            --log-file="$work/valgrind-$mode.log" \
            "$python" scripts/memory_host.py "$work/build" "$mode" >"$work/host-$mode.out" 2>&1 || status=$?
        sed "s/^/    /" "$work/host-$mode.out"
        if "$python" scripts/valgrind_findings.py "$work/valgrind-$mode.xml" "$mode" "$status" "$work/valgrind-$mode.log"
        then
            echo "memory 2/2 (valgrind): $mode: clean ($(took "$step"))"
        else
            echo "memory 2/2 (valgrind): $mode: FAILED ($(took "$step"))"
            failed+=("valgrind $mode")
        fi
    done
    echo "memory 2/2 (valgrind): done ($(took "$part"))"
fi

if [ ${#failed[@]} -gt 0 ]; then
    echo "memory check: FAILED: $(printf '%s; ' "${failed[@]}")($(took "$started") in all)"
    exit 1
fi
echo "memory check: no finding ($(took "$started") in all)"
