"""The memory check (scripts/check_memory.sh) can fail: a tiny shared library with deliberate memory errors,
loaded by a tiny C host, is caught by AddressSanitizer, UndefinedBehaviorSanitizer and LeakSanitizer with
the flags and options the check uses (tests/sanitize.py), and by valgrind with the check's suppressions and
its reading of the log (scripts/valgrind_findings.py), including a read of freed memory while the process
exits, as pythonfmu's finalizePythonInterpreter does; a library without errors passes both."""

from __future__ import annotations

import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import sanitize

from double_pendulum.fmu.build import loader

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"

pytestmark = [
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the memory check is for the Linux binaries"),
    pytest.mark.skipif(loader.c_compiler() is None, reason="no C compiler ($CC, cc, gcc or clang)"),
]

BROKEN = textwrap.dedent("""
    #include <limits.h>
    #include <stdlib.h>

    static volatile char *kept;

    int fine(int x) { volatile char *p = malloc(16); p[15] = (char)x; int v = p[15]; free((void *)p); return v; }
    int heap_overflow(int x) {  /* a size known only at run time: AddressSanitizer's finding, not UBSan's object-size */
        volatile char *p = malloc(15 + x); p[16] = (char)x; int v = p[16]; free((void *)p); return v;
    }
    int use_after_free(int x) { volatile char *p = malloc(16); p[0] = (char)x; free((void *)p); return p[0]; }
    int signed_overflow(int x) { return x + INT_MAX; }
    int leak(int x) { volatile char *p = malloc(4096); p[0] = (char)x; p = NULL; return x; }

    /* What pythonfmu's library does at exit: an atexit handler frees a block, then the library's
       destructor (run later, by the dynamic loader's fini) reads it. */
    static void free_kept(void) { free((void *)kept); }
    int exit_time_use_after_free(int x) { kept = malloc(128); kept[8] = (char)x; atexit(free_kept); return x; }
    __attribute__((destructor)) static void at_unload(void) { if (kept) (void)kept[8]; }
""")

HOST = textwrap.dedent("""
    #include <dlfcn.h>
    #include <stdio.h>

    int main(int argc, char **argv) {
        if (argc != 3) return 2;
        void *library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
        if (!library) { fprintf(stderr, "%s\\n", dlerror()); return 3; }
        int (*call)(int) = (int (*)(int))dlsym(library, argv[2]);
        if (!call) { fprintf(stderr, "no %s\\n", argv[2]); return 4; }
        printf("result %d\\n", call(1));
        return 0; /* exits with the library loaded, as a host that never unloads an FMU */
    }
""")


def compile_pair(folder: Path, flags: list[str]) -> tuple[Path, Path]:
    """The broken library (as an FMU's binary: under binaries/linux64/) and the host, compiled with ``flags``."""
    (folder / "broken.c").write_text(BROKEN)
    (folder / "host.c").write_text(HOST)
    library = folder / "binaries" / "linux64" / "libbroken.so"
    library.parent.mkdir(parents=True)
    compiler = loader.c_compiler()
    subprocess.run([*compiler, *flags, "-shared", "-fPIC", "-o", str(library), str(folder / "broken.c")], check=True,
                   capture_output=True)
    host = folder / "host"
    subprocess.run([*compiler, *flags, "-o", str(host), str(folder / "host.c"), "-ldl"], check=True,
                   capture_output=True)
    return library, host


@pytest.fixture(scope="module")
def sanitized(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    return compile_pair(tmp_path_factory.mktemp("sanitized"), list(sanitize.FLAGS))


@pytest.mark.parametrize(("function", "report"), [
    ("heap_overflow", "ERROR: AddressSanitizer: heap-buffer-overflow"),
    ("use_after_free", "ERROR: AddressSanitizer: heap-use-after-free"),
    ("exit_time_use_after_free", "ERROR: AddressSanitizer: heap-use-after-free"),
    ("signed_overflow", "runtime error: signed integer overflow"),
    ("leak", "ERROR: LeakSanitizer: detected memory leaks"),
])
def test_the_sanitizers_catch_each_error_with_the_checks_options(sanitized, tmp_path, function, report):
    library, host = sanitized
    done = subprocess.run([str(host), str(library), function], capture_output=True, text=True, timeout=60,
                          env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), **sanitize.options()}, cwd=tmp_path)
    assert done.returncode != 0, done.stdout + done.stderr
    assert report in done.stderr, done.stderr
    assert "broken.c" in done.stderr, "the report names the library's source line"


def test_a_library_without_errors_passes_the_sanitizers(sanitized, tmp_path):
    library, host = sanitized
    done = subprocess.run([str(host), str(library), "fine"], capture_output=True, text=True, timeout=60,
                          env={"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), **sanitize.options()}, cwd=tmp_path)
    assert done.returncode == 0 and done.stdout == "result 1\n" and not done.stderr, done.stdout + done.stderr


@pytest.fixture(scope="module")
def plain(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    if shutil.which("valgrind") is None:
        pytest.skip("no valgrind here (scripts/check_memory.sh installs Debian's where it runs as root)")
    return compile_pair(tmp_path_factory.mktemp("plain"), ["-O0", "-g"])


def valgrind(library: Path, host: Path, function: str, folder: Path) -> tuple[int, str]:
    """The host under valgrind as check_memory.sh runs it, then valgrind_findings.py on the log: its exit
    status and what it says."""
    xml, log = folder / f"{function}.xml", folder / f"{function}.log"
    done = subprocess.run(["valgrind", "--num-callers=24", "--error-exitcode=99", "--errors-for-leak-kinds=none",
                           "--show-leak-kinds=none",
                           f"--suppressions={SCRIPTS / 'valgrind-python.supp'}", "--xml=yes", f"--xml-file={xml}",
                           f"--log-file={log}", str(host), str(library), function],
                          capture_output=True, text=True, timeout=60)
    findings = subprocess.run([sys.executable, str(SCRIPTS / "valgrind_findings.py"), str(xml), function,
                               str(done.returncode), str(log)], capture_output=True, text=True, timeout=60)
    return findings.returncode, findings.stdout


@pytest.mark.parametrize(("function", "error", "where"), [
    ("heap_overflow", "Invalid write of size 1", "heap_overflow (broken.c:"),
    ("use_after_free", "Invalid read of size 1", "use_after_free (broken.c:"),
    ("exit_time_use_after_free", "Invalid read of size 1", "at_unload (broken.c:"),
])
def test_valgrind_and_its_reading_catch_each_error_in_the_fmus_binaries(plain, tmp_path, function, error, where):
    status, said = valgrind(*plain, function, tmp_path)
    assert status == 1, said
    assert f"valgrind {function}: [FMU] {error}" in said and where in said, said
    assert "of these contexts in the FMU's binaries" in said and "FAILED" in said, said


def test_a_library_without_errors_passes_valgrind(plain, tmp_path):
    status, said = valgrind(*plain, "fine", tmp_path)
    assert status == 0, said
    assert "valgrind fine: no error in the FMU's binaries or anywhere else" in said, said
