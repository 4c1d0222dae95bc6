"""The Python half of the FMU's binary: what the C loader calls (its C half: ``loader/bridge.c``).

The loader calls the FMU's slave object (pythonfmu's ``Fmi2Slave`` API for FMI 2, pythonfmu3's
``Fmi3SlaveBase`` for FMI 3) through one :class:`Instance` per FMI instance; no FMI library's binary
stands between them. Every method the loader calls answers ``(status, payload, messages)`` and never
raises:

* ``status``: FMI's number (0 OK, 1 Warning, 2 Discard, 3 Error), or :data:`INTERRUPTED` when a
  Ctrl-C (``KeyboardInterrupt``) stopped the call, or :data:`HOST` when another exception of the host's
  stopped it (:func:`host_exception`: one its signal handler raised, ``SystemExit``, any ``BaseException``
  that is not an ``Exception``): the loader answers fmi2Error / fmi3Error and raises the interrupt, or the
  host's own exception object, again in the host's thread once the call has returned;
* ``payload``: bytes of packed values (``struct``'s native formats, :data:`FORMATS`), UTF-8 strings
  each ended by NUL, or an object (a slave, an FMU state) the loader keeps;
* ``messages``: what the slave logged during the call, then why it failed, as
  ``(status, category, text)``. The loader gives them to the host's logger after it has let go of the
  GIL, so no lock is held while the host's callback runs.

An exception is an error of its instance only, said in one line (``ParameterError: invalid ...``);
nothing is printed to the host's stderr. Standard library only: it runs in whatever CPython the loader
found, with nothing installed.
"""

from __future__ import annotations

import json
import os
import struct
import sys
from typing import Any

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3
INTERRUPTED = 5  # a KeyboardInterrupt stopped the call (loader/bridge.h, BRIDGE_INTERRUPTED)
HOST = 6  # another exception of the host's stopped it; the payload: its redelivery (bridge.h, BRIDGE_HOST)
# The FMI types' values as the C side packs them (fmi2Boolean is an int, fmi3Boolean a C bool).
FORMATS = {
    2: {"Real": "d", "Integer": "i", "Boolean": "i"},
    3: {"Float64": "d", "Int32": "i", "Int64": "q", "UInt64": "Q", "Boolean": "?"},
}

Answer = tuple[int, Any, tuple]
DISCARDED = object()  # what a call that was not completed returns (fmi2Discard / fmi3Discard)


class Refusal(ValueError):
    """A call this FMU refuses, in words that need no exception's name (a value reference it does not have)."""


def describe(error: BaseException) -> str:
    """An exception in one line: ``ParameterError: invalid phi1_0 = nan rad: must be finite``."""
    text = str(error).strip().replace("\n", " ")
    if isinstance(error, Refusal):
        return text
    return f"{type(error).__name__}: {text}" if text else type(error).__name__


def host_exception(error: BaseException) -> bool:
    """Whether ``error`` is the host's own, not a failure of the model: a ``BaseException`` that is not an
    ``Exception`` (``SystemExit``, ``KeyboardInterrupt``, ``GeneratorExit``, ...), or an exception raised by one
    of the host's Python signal handlers (the ``signal.alarm`` pattern, pytest-timeout's signal method) while the
    FMU ran: one of its traceback's frames runs a handler's code."""
    if not isinstance(error, Exception):
        return True
    # Python signal handlers exist only where the host imported the signal module: never import it here (its
    # first import installs CPython's SIGINT handler, which a C host's process must not get from the FMU)
    _signal = sys.modules.get("_signal")
    if _signal is None:
        return False
    handlers = set()
    for number in _signal.valid_signals():
        try:
            handler = _signal.getsignal(number)
        except (OSError, ValueError):
            continue
        code = getattr(getattr(handler, "__func__", handler), "__code__", None)
        if code is not None:
            handlers.add(code)
    frame = error.__traceback__
    while frame is not None:
        if frame.tb_frame.f_code in handlers:
            return True
        frame = frame.tb_next
    return False


def redelivery(error: BaseException) -> type:
    """A class whose call gives back ``error`` itself: what the loader raises again in the host's thread
    (``PyThreadState_SetAsyncExc`` takes a class, and CPython makes the exception by calling it), so that the
    host catches its own exception object, with its traceback through the FMU."""

    class HostException(BaseException):
        def __new__(cls, *args):
            return error

    return HostException


def host_answer(error: BaseException, messages: tuple) -> Answer:
    """The answer of a call the host's own exception stopped: Error with its line, and its redelivery."""
    said = (ERROR, "logStatusError", f"the host's own {describe(error)} stopped the call, which was not completed; "
            "it is raised again in the host, and a reset makes the instance usable again")
    return HOST, redelivery(error), messages + (said,)


def escaped_answer(error: BaseException) -> Answer | None:
    """For an exception that escaped a call before its answer was made (a signal handler runs as a Python function
    starts, before its ``try``): the call's answer (:func:`host_answer`) if it is the host's own
    (:func:`host_exception`), else None. The loader asks it of the object it called (:class:`Bridge`,
    :class:`Instance`) and reads it as any answer."""
    return host_answer(error, ()) if host_exception(error) else None


def _unpack(code: str, data: bytes) -> list:
    return list(struct.unpack(f"={len(data) // struct.calcsize(code)}{code}", data))


class Bridge:
    """What an FMU's entry module exposes as ``fmi_bridge``: its slave class and FMI version."""

    escaped_answer = staticmethod(escaped_answer)

    def __init__(self, model_class: type, fmi_version: int) -> None:
        self.model_class = model_class
        self.fmi_version = fmi_version
        self.formats = FORMATS[fmi_version]

    def instantiate(self, resources: bytes, name: str, interface: str, visible: int) -> Answer:
        """A new :class:`Instance` (the payload), for ``interface`` ("CoSimulation", "ModelExchange"); the
        resources folder's path comes as bytes (``os.fsdecode``: the same folder in any encoding)."""
        try:
            return OK, Instance(self, os.fsdecode(resources), name, interface, bool(visible)), ()
        except KeyboardInterrupt:
            return INTERRUPTED, None, ()  # the loader logs the one text of an interrupt
        except BaseException as error:
            if host_exception(error):
                return host_answer(error, ())
            return ERROR, None, ((ERROR, "logStatusError", describe(error)),)


class Instance:
    """One FMI instance: its slave, and every call the loader makes on it."""

    escaped_answer = staticmethod(escaped_answer)

    def __init__(self, bridge: Bridge, resources: str, name: str, interface: str, visible: bool) -> None:
        self.bridge, self.resources, self.name, self.visible = bridge, resources, name, visible
        self.model_exchange = interface == "ModelExchange"
        self.slave = self._new_slave()

    def _new_slave(self):
        slave = self.bridge.model_class(instance_name=self.name, resources=self.resources, visible=self.visible)
        if hasattr(slave, "use_interface"):
            slave.use_interface(self.model_exchange)
        return slave

    # ---------------------------------------------------------------- the call
    def _run(self, call, *args) -> Answer:
        """``call(*args)`` as an answer: its payload, or its exception as an error line."""
        try:
            payload = call(*args)
            if payload is DISCARDED:
                return DISCARD, None, self._messages()
            return OK, payload, self._messages()
        except KeyboardInterrupt:
            return INTERRUPTED, None, self._messages()  # the loader logs the one text of an interrupt
        except BaseException as error:
            if host_exception(error):
                return host_answer(error, self._messages())
            return ERROR, None, self._messages((ERROR, "logStatusError", describe(error)))

    def _messages(self, *last: tuple) -> tuple:
        """What the slave logged since the last call, then ``last``."""
        queue = getattr(self.slave, "log_queue", None) or []
        logged = tuple((int(getattr(m.status, "value", m.status)), m.category or "", str(m.msg)) for m in queue)
        queue.clear()
        return logged + last

    # ---------------------------------------------------------------- lifetime
    def reset(self) -> Answer:
        """fmiXReset: the slave made anew (its start values too)."""
        def renew():
            old, self.slave = self.slave, None
            _release(old)
            self.slave = self._new_slave()
        return self._run(renew)

    def release(self) -> Answer:
        """Before the loader lets go of this instance: the slave's reference cycles (its variables' getters
        and setters close over it) are broken, so that it is freed at once, not at the next collection."""
        slave, self.slave = self.slave, None
        return self._run(_release, slave)

    # ---------------------------------------------------------------- modes
    def setup_experiment(self, start: float, stop_defined: int, stop: float, tolerance_defined: int,
                         tolerance: float) -> Answer:
        if self.bridge.fmi_version == 2:
            return self._run(self.slave.setup_experiment, start, stop if stop_defined else None,
                             tolerance if tolerance_defined else None)
        return self._run(self.slave.setup_experiment, start)

    def enter_initialization_mode(self) -> Answer:
        return self._run(self.slave.enter_initialization_mode)

    def exit_initialization_mode(self) -> Answer:
        return self._run(self.slave.exit_initialization_mode)

    def terminate(self) -> Answer:
        return self._run(self.slave.terminate)

    def enter_event_mode(self) -> Answer:
        return self._run(getattr(self.slave, "enter_event_mode", _nothing))

    def enter_continuous_time_mode(self) -> Answer:
        return self._run(getattr(self.slave, "enter_continuous_time_mode", _nothing))

    def enter_step_mode(self) -> Answer:
        return self._run(getattr(self.slave, "enter_step_mode", _nothing))

    def do_step(self, current_time: float, step_size: float, no_set_prior: int) -> Answer:
        """A communication step: OK, or Discard where the slave could not complete it."""
        def step():
            return DISCARDED if self.slave.do_step(current_time, step_size) is False else None
        return self._run(step)

    # ---------------------------------------------------------------- values
    def get(self, type_name: str, references: bytes) -> Answer:
        return self._run(self._get, type_name, references)

    def set(self, type_name: str, references: bytes, values: bytes) -> Answer:
        return self._run(self._set, type_name, references, values)

    def get_strings(self, references: bytes) -> Answer:
        def get():
            values = self._access("get", "String", _unpack("I", references))
            text = [str(value) for value in values]
            for vr, value in zip(_unpack("I", references), text):
                if "\0" in value:
                    raise Refusal(f"the String of valueReference {vr} holds a NUL character")
            return b"".join(value.encode("utf-8") + b"\0" for value in text)
        return self._run(get)

    def set_strings(self, references: bytes, joined: bytes) -> Answer:
        values = [part.decode("utf-8") for part in joined.split(b"\0")[:-1]]
        return self._run(self._access, "set", "String", _unpack("I", references), values)

    def _get(self, type_name: str, references: bytes) -> bytes:
        code = self.bridge.formats[type_name]
        values = self._access("get", type_name, _unpack("I", references))
        return struct.pack(f"={len(values)}{code}", *values)

    def _set(self, type_name: str, references: bytes, data: bytes):
        code = self.bridge.formats[type_name]
        values = _unpack(code, data)
        if type_name == "Boolean":
            values = [value != 0 for value in values]
        return self._access("set", type_name, _unpack("I", references), values)

    def _access(self, kind: str, type_name: str, vrs: list, *values):
        """The slave's get_<type> / set_<type>; a wrong value reference or type said as such."""
        method = getattr(self.slave, f"{kind}_{type_name.lower()}")
        try:
            return method(vrs, *values)
        except (KeyError, TypeError) as error:
            self._check_references(type_name, vrs)
            raise error

    def _check_references(self, type_name: str, vrs: list) -> None:
        variables = self.slave.vars
        for k, vr in enumerate(vrs):
            variable = variables.get(vr)
            if variable is None:
                raise Refusal(f"valueReference {vr} (element {k}) is not a variable of this FMU")
            if type(variable).__name__ != type_name:
                raise Refusal(f"valueReference {vr} ({variable.name}) is a {type(variable).__name__} variable, "
                                f"not a {type_name}")

    # ---------------------------------------------------------------- FMU states
    def _noted(self, answer: Answer, say) -> Answer:
        """``answer`` with, where it is OK, the debug line (logAll) ``say(payload)``: what a state call did."""
        status, payload, messages = answer
        if status != OK:
            return answer
        return status, payload, messages + ((OK, "logAll", say(payload)),)

    def get_fmu_state(self) -> Answer:
        return self._noted(self._run(self.slave._get_fmu_state),
                           lambda state: f"the FMU state at t = {self.slave.fmu_state_time(state)!r} s")

    def set_fmu_state(self, state) -> Answer:
        return self._noted(self._run(self.slave._set_fmu_state, state),
                           lambda _: f"back to the FMU state at t = {self.slave.fmu_state_time(state)!r} s")

    def serialize_fmu_state(self, state) -> Answer:
        return self._noted(self._run(lambda: json.dumps(state, allow_nan=True).encode("utf-8")),
                           lambda data: f"the FMU state at t = {self.slave.fmu_state_time(state)!r} s is {len(data)} "
                           "bytes of JSON")

    def deserialize_fmu_state(self, data: bytes, time: float) -> Answer:
        """The state in ``data``, checked completely before anything uses it; ``time`` [s] is the loader's header's,
        which must be the state's own time (a tampered time is refused here, not at the next step)."""
        def load():
            try:
                state = json.loads(data.decode("utf-8"))
            except (UnicodeDecodeError, ValueError) as error:
                raise Refusal(f"the state is malformed: its bytes are not JSON ({error})") from None
            try:
                self.slave.check_fmu_state(state)
            except (ValueError, TypeError, KeyError, LookupError) as error:
                raise Refusal(f"the state is malformed: {error}") from None
            own = self.slave.fmu_state_time(state)
            if own != time:
                raise Refusal(f"the state is malformed: its header's time {time!r} s is not its payload's {own!r} s")
            return state
        return self._noted(self._run(load), lambda _: f"a serialized FMU state at t = {time!r} s, checked")

    # ---------------------------------------------------------------- Model Exchange
    def set_time(self, time: float) -> Answer:
        return self._run(self.slave.set_time, time)

    def set_continuous_states(self, data: bytes) -> Answer:
        return self._run(self.slave.set_continuous_states, _unpack("d", data))

    def get_continuous_states(self) -> Answer:
        return self._run(lambda: _pack_floats(self.slave.get_continuous_states()))

    def get_continuous_state_derivatives(self) -> Answer:
        return self._run(lambda: _pack_floats(self.slave.get_continuous_state_derivatives()))

    def get_nominals_of_continuous_states(self) -> Answer:
        def nominals():
            n = self.slave.get_number_of_continuous_states()
            return _pack_floats(self.slave.get_nominals_of_continuous_states(n))
        return self._run(nominals)

    def get_event_indicators(self) -> Answer:
        return self._run(lambda: _pack_floats(self.slave.get_event_indicators()))

    def update_discrete_states(self) -> Answer:
        def update():
            r = self.slave.update_discrete_states()
            flags = [bool(getattr(r, name, False)) for name in (
                "discreteStatesNeedUpdate", "terminateSimulation", "nominalContinuousStatesChanged",
                "valuesOfContinuousStatesChanged", "nextEventTimeDefined")]
            return struct.pack("=5?d", *flags, float(getattr(r, "nextEventTime", 0.0)) if flags[4] else 0.0)
        return self._run(update)

    def completed_integrator_step(self, no_set_prior: int) -> Answer:
        return self._run(lambda: struct.pack("=2?", False, False))  # no events: never enter Event Mode


def _pack_floats(values) -> bytes:
    values = list(values)
    return struct.pack(f"={len(values)}d", *values)


def _nothing() -> None:
    return None


def _release(slave) -> None:
    """Break a slave's reference cycles (see :meth:`Instance.release`)."""
    if slave is not None:
        getattr(slave, "__dict__", {}).clear()
