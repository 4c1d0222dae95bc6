"""Straight-line functions assembled from equation snippets, compiled once.

The hot vector fields (the frictionless pendulum, fixed or on a driven pivot) are called a dozen
times per integrator step; as Python closures calling helper functions, the calls and tuple
packing cost as much as the arithmetic. Each equation therefore lives once, as a *snippet*: a few
lines of plain assignments in the module that owns it (e.g.
:data:`double_pendulum.model.dynamics.LINK_ACCELERATIONS`). :func:`compile_function` joins
snippets into one function body, compiles it once per source text and binds it to the constants
of a scene (masses, lengths, ...) as its globals, so every call is one frame of straight-line
float arithmetic. The same snippets also build the plain helper functions (e.g.
:func:`double_pendulum.model.dynamics.link_accelerations`), so there is one copy of each equation.

Snippets hold only assignments of arithmetic expressions over named values and the functions
given in the namespace; nothing from outside enters the generated source.
"""

from __future__ import annotations

import builtins
import textwrap
import types
from collections.abc import Callable, Mapping, Sequence
from functools import cache
from typing import Any


@cache
def _code(name: str, parameters: str, body: str, returns: str) -> types.CodeType:
    source = f"def {name}({parameters}):\n{textwrap.indent(body, '    ')}    return {returns}\n"
    module = compile(source, f"<{name}>", "exec")
    return next(c for c in module.co_consts if isinstance(c, types.CodeType))


def compile_function(
    name: str,
    parameters: str,
    snippets: Sequence[str],
    returns: str,
    constants: Mapping[str, Any],
    *,
    defaults: tuple[Any, ...] = (),
    doc: str | None = None,
) -> Callable[..., Any]:
    """Return ``def name(parameters): <snippets, in order>; return returns`` with ``constants`` as globals.

    ``parameters`` is the parameter list without defaults; ``defaults`` fills its last ones (as a
    function's ``__defaults__``). The code is compiled once per source text; each call of this
    function only binds a new set of constants.
    """
    body = "".join(textwrap.dedent(snippet).strip("\n") + "\n" for snippet in snippets)
    namespace = {"__builtins__": builtins, **constants}
    function = types.FunctionType(_code(name, parameters, body, returns), namespace, name, defaults or None)
    function.__doc__ = doc
    return function
