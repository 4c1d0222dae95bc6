"""Command line: the ``double-pendulum`` command (:mod:`.run`, to be split by command)."""

from .run import build_parser, entry, main

__all__ = ["build_parser", "entry", "main"]
