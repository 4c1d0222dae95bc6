"""Ctrl-C within a run: an interrupt Python cannot raise (in a finaliser or a weakref callback) leaves no traceback
on stderr; any other unraisable exception is still reported. In a fresh interpreter (pytest has its own hook)."""

from __future__ import annotations

import subprocess
import sys

SCRIPT = """
import gc, sys, weakref
from double_pendulum.runs import interrupts

class Raises:
    def __init__(self, error):
        self.error = error
    def __del__(self):
        raise self.error("from a finaliser")

def collect(error):
    Raises(error)
    gc.collect()

class Key:
    pass

def lost_in_a_weak_key_dictionary():
    table = weakref.WeakKeyDictionary()
    key = Key()
    table[key] = 1
    weakref.finalize(key, lambda: (_ for _ in ()).throw(KeyboardInterrupt("in a weakref callback")))
    del key
    gc.collect()

if sys.argv[1] == "run":
    with interrupts.handling_interrupts():
        collect(KeyboardInterrupt)
        lost_in_a_weak_key_dictionary()
        collect(ValueError)
else:
    collect(KeyboardInterrupt)
"""


def _stderr(mode: str) -> str:
    return subprocess.run([sys.executable, "-c", SCRIPT, mode], capture_output=True, text=True, timeout=60).stderr


def test_an_interrupt_lost_in_a_finaliser_prints_no_traceback_while_the_run_handles_ctrl_c():
    err = _stderr("run")
    assert "KeyboardInterrupt" not in err and "in a weakref callback" not in err
    assert "ValueError: from a finaliser" in err and "Exception ignored" in err  # real errors still show


def test_outside_a_run_python_reports_it_as_usual():
    assert "KeyboardInterrupt: from a finaliser" in _stderr("plain")


ENDING = """
import os, signal, sys, time
from double_pendulum.runs import interrupts

signal.signal(signal.SIGINT, signal.default_int_handler)  # the caller's handler: Python's, whatever was inherited

if sys.argv[1] == "process":
    interrupts.ends_the_process()
try:
    with interrupts.handling_interrupts():
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt:
            interrupts.acknowledge()
        raise ImportError("initialization failed")  # what a C extension makes of an interrupt in its import
except KeyboardInterrupt:
    print("interrupt, not the error", flush=True)
os.kill(os.getpid(), signal.SIGINT)  # a second Ctrl-C after the clean-up, as the process ends
time.sleep(0.2)
print("still here", flush=True)
sys.exit(130)
"""


def test_after_an_interrupted_run_the_ending_process_ignores_ctrl_c_and_errors_are_the_interrupt():
    """An error leaving the run after Ctrl-C is the interrupt (KeyboardInterrupt); in the command's own process a
    later Ctrl-C, after the clean-up, is ignored through exit (status 130, no traceback). A run started from
    Python (no ends_the_process) gets the caller's handler back, so the same Ctrl-C is Python's KeyboardInterrupt."""
    ending = subprocess.run([sys.executable, "-c", ENDING, "process"], capture_output=True, text=True, timeout=60)
    assert ending.returncode == 130, ending.stderr
    assert ending.stdout.split("\n")[:2] == ["interrupt, not the error", "still here"]
    assert "Traceback" not in ending.stderr
    embedded = subprocess.run([sys.executable, "-c", ENDING, "python"], capture_output=True, text=True, timeout=60)
    assert embedded.stdout.startswith("interrupt, not the error") and "still here" not in embedded.stdout
    assert "KeyboardInterrupt" in embedded.stderr
