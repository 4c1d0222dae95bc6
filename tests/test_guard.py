"""The FMUs' C loader (``fmu_src/loader/fmi2_guard.c``, ``fmi3_guard.c``, ``guard.c``), tried as the
test suites of FMI tools would: torture hosts in C (``tests/c_host/fmi2_torture.c``, ``fmi3_torture.c``),
started with a bare environment, make every call a master may get wrong and check that each gets what
the standard says (FMI 2.0 sections 2.1 and 4.2.4, FMI 3.0 sections 2.2, 3.2 and 4.2) with a log line
that says why: no crash, no hang. Then many threads at once, neighbours of the same names, and
memory over thousands of instantiate/free cycles.

With DOUBLE_PENDULUM_SANITIZE=1 (scripts/check_memory.sh, tests/sanitize.py) the same hosts and FMUs are
built with AddressSanitizer and UndefinedBehaviorSanitizer: every probe, the threads and a shorter soak
then also prove that no call reads or writes memory it should not; the tests that load the FMU into
this Python process (fmpy) skip, since a sanitized loader runs only in a sanitized host."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import sanitize
from foreign_fmu import RATE, START, build_foreign_fmu
from host_binaries import compiled_host

from double_pendulum.fmu.build import loader

NO_LOG = ""  # expected fragment: the call logs nothing
# Instantiate/free cycles of the soak, one run (the fixture soak) for both soak tests: fewer under the sanitizers
# (about 2.5 ms a cycle there); the host reports resident memory every SOAK_EVERY cycles.
SOAK_CYCLES = 500 if sanitize.ENABLED else 4000
SOAK_EVERY = 100
in_this_process = pytest.mark.skipif(sanitize.ENABLED, reason="a sanitized loader runs only in the sanitized C hosts, "
                                                               "not in this Python process")

pytestmark = [
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the C loader and these C hosts are for Linux"),
    pytest.mark.skipif(loader.c_compiler() is None, reason="no C compiler ($CC, cc, gcc or clang) to build the hosts"),
]

# probe: (status it must get, a fragment of its log line; None: not checked, NO_LOG: no line). The status
# of fmi2Instantiate probes is 0 for NULL (refused), 1 for an instance; probes of a whole sequence say 0
# (or the discard's 2) when every step went as the standard says.
FMI2_PROBES = {
    "exit_without_enter": (3, "fmi2ExitInitializationMode: illegal call sequence: not allowed in state Instantiated"),
    "enter_twice": (3, "fmi2EnterInitializationMode: illegal call sequence: not allowed in state Initialization Mode"),
    "exit_twice": (3, "fmi2ExitInitializationMode: illegal call sequence: not allowed in state Step Complete"),
    "terminate_twice": (3, "fmi2Terminate: illegal call sequence: not allowed in state Terminated"),
    "terminate_before_initialisation": (3, "fmi2Terminate: illegal call sequence: not allowed in state Instantiated"),
    "set_real_after_terminate": (3, "fmi2SetReal: illegal call sequence: not allowed in state Terminated"),
    "do_step_after_terminate": (3, "fmi2DoStep: illegal call sequence: not allowed in state Terminated"),
    "setup_experiment_in_step_mode": (3, "fmi2SetupExperiment: illegal call sequence: not allowed in state Step"),
    "do_step_before_initialisation": (3, "fmi2DoStep: illegal call sequence: not allowed in state Instantiated"),
    "get_real_when_instantiated": (3, "fmi2GetReal: illegal call sequence: not allowed in state Instantiated"),
    "step_size_zero": (3, "fmi2DoStep: communicationStepSize = 0 s must be finite and > 0"),
    "step_size_negative": (3, "communicationStepSize = -0.01 s must be finite and > 0"),
    "step_size_nan": (3, "communicationStepSize = nan s must be finite and > 0"),
    "step_size_infinite": (3, "communicationStepSize = inf s must be finite and > 0"),
    "communication_point_nan": (3, "currentCommunicationPoint = nan s is not the FMU's time 0 s"),
    "communication_point_not_the_fmus_time": (3, "currentCommunicationPoint = 0.5 s is not the FMU's time 0 s"),
    "error_state_then_reset": (0, "fmi2DoStep: illegal call sequence: not allowed in state Error"),
    "start_value_nan": (3, "fmi2SetReal: ParameterError: invalid phi1_0 = nan rad: must be finite"),
    "negative_mass": (3, "invalid m1 = -0.3 kg: must be > 0"),
    "unknown_value_reference": (3, "fmi2SetReal: valueReference 999999 (element 0) is not a variable of this FMU"),
    "unknown_solver": (3, "fmi2SetString: UnknownSolverError: invalid solver = 'radau5'"),
    "wrong_type": (3, "fmi2GetBoolean: valueReference 55 (phi1) is a Real variable, not a Boolean"),
    "fixed_parameter_after_initialisation": (3, "cannot set parameter l1 = 0.5 after initialisation"),
    "errors_leave_siblings_working": (0, "invalid input pivot_ax = nan"),
    "wrong_guid": (0, 'fmi2Instantiate: fmuGUID "{wrong}" is not this FMU\'s'),
    "empty_guid": (0, 'fmuGUID "" is not this FMU\'s'),
    "null_guid": (0, "fmuGUID NULL is not this FMU's"),
    "model_exchange": (0, "fmuType = 0: this FMU supports co-simulation (fmi2CoSimulation = 1) only"),
    "null_instance_name": (0, "fmi2Instantiate: instanceName is NULL"),
    "empty_instance_name": (0, "fmi2Instantiate: instanceName is empty"),
    "instance_name_not_utf8": (0, "fmi2Instantiate: instanceName is not UTF-8 (byte 1 is 0xff"),
    "null_resource_location": (0, "fmuResourceLocation is NULL"),
    "missing_resource_folder": (0, "there is no folder /nonexistent/resources"),
    "foreign_resource_folder": (0, "is not this FMU's resources folder (no identity.cfg in /tmp)"),
    "null_callbacks": (0, NO_LOG),
    "null_logger": (0, NO_LOG),
    "format_directives_in_a_string": (3, "invalid solver = '%s%s%s%n%n%p'"),
    "get_real_null_references": (3, "fmi2GetReal: vr is NULL with nvr = 2"),
    "get_real_null_values": (3, "fmi2GetReal: value is NULL with nvr = 2"),
    "set_real_null_values": (3, "fmi2SetReal: value is NULL with nvr = 2"),
    "get_integer_null_values": (3, "fmi2GetInteger: value is NULL"),
    "get_boolean_null_references": (3, "fmi2GetBoolean: vr is NULL"),
    "get_string_null_values": (3, "fmi2GetString: value is NULL"),
    "set_boolean_null_values": (3, "fmi2SetBoolean: value is NULL"),
    "set_integer_null_references": (3, "fmi2SetInteger: vr is NULL"),
    "zero_values_need_no_arrays": (0, NO_LOG),
    "get_real_huge_count": (3, "fmi2GetReal: nvr = 4611686018427387905, but this FMU has "),
    "set_real_huge_count": (3, "fmi2SetReal: nvr = 4611686018427387904, but this FMU has "),
    "get_integer_huge_count": (3, "fmi2GetInteger: nvr = 4611686018427387905, but this FMU has "),
    "get_string_huge_count": (3, "fmi2GetString: nvr = 4611686018427387905, but this FMU has "),
    "get_real_more_references_than_variables": (3, "fmi2GetReal: nvr = 1000, but this FMU has "),
    "set_string_null_element": (3, "fmi2SetString: value[0] (vr = "),
    "set_string_not_utf8": (3, ") is not UTF-8 (byte 3 is 0xe9; an fmi2String is UTF-8 encoded)"),
    "debug_logging_null_categories": (3, "fmi2SetDebugLogging: categories is NULL with nCategories = 2"),
    "debug_logging_unknown_category": (3, 'unknown log category "logEverything"'),
    "debug_logging_null_category": (3, "fmi2SetDebugLogging: categories[1] is NULL"),
    "errors_silenced_by_set_debug_logging": (3, NO_LOG),
    "get_fmu_state_null": (3, "fmi2GetFMUstate: FMUstate is NULL"),
    "set_fmu_state_null": (3, "fmi2SetFMUstate: the FMU state is NULL"),
    "set_fmu_state_foreign_pointer": (3, "is not a live state of this FMU"),
    "free_fmu_state_null_pointer": (3, "fmi2FreeFMUstate: FMUstate is NULL"),
    "free_fmu_state_null_state": (0, NO_LOG),
    "serialized_size_null": (3, "fmi2SerializedFMUstateSize: size is NULL"),
    "deserialize_garbage": (3, "bytes are not a serialized state of this FMU (no header)"),
    "deserialize_null_bytes": (3, "fmi2DeSerializeFMUstate: serializedState is NULL"),
    "real_status_null_value": (3, "fmi2GetRealStatus: value is NULL"),
    "real_status_unknown_kind": (3, "fmi2GetRealStatus: 99 is not an fmi2StatusKind"),
    "status_kind_not_given": (2, NO_LOG),  # fmi2Discard (the standard's answer); Discard messages are debug
    "last_successful_time": (0, NO_LOG),
    "directional_derivative": (3, "providesDirectionalDerivative = false"),
    "input_derivatives": (3, "canInterpolateInputs = false"),
    "output_derivatives": (3, "maxOutputDerivativeOrder = 0"),
    "cancel_step": (3, "fmi2CancelStep: illegal call sequence"),
    "null_instance_do_step": (3, NO_LOG),  # no instance to log through: stderr (ORPHANS)
    "null_instance_set_real": (3, NO_LOG),
    "null_instance_free": (0, NO_LOG),
    "freed_instance_used": (3, NO_LOG),
    "freed_twice": (0, NO_LOG),
    "fmu_state_restores_the_time": (0, "currentCommunicationPoint = 1 s is not the FMU's time 0.5 s"),
    "serialized_state_in_a_new_instance": (0, NO_LOG),
    "tampered_state_header_time": (3, "the state is malformed: its header's time 1e+308 s is not its payload's "
                                      "0.125 s"),
    "tampered_state_last_successful_time": (3, "the state is malformed: its header holds FMI state 4 at t = 0.125 s "
                                               "(last successful time 1 s)"),
    "tampered_state_payload_time": (3, "the state is malformed: its header's time 0.125 s is not its payload's "
                                       "1e+308 s"),
    "discarded_step_then_terminate": (2, "fmi2DoStep: the step was not completed: numerical instability at t = "),
    "do_step_after_discard": (3, "fmi2DoStep: illegal call sequence: not allowed in state Step Failed"),
    # what the FMU leaves to the host (the first instantiation of a process: OWN_PROCESS_PROBES below)
    "locale_unchanged": (0, NO_LOG),
    "host_state_unchanged": (0, NO_LOG),  # environment, handlers of SIGINT ... SIGSEGV, signal mask
    "stdio_unlocked_after_instantiate": (0, NO_LOG),  # ftrylockfile(stderr / stdout) from another thread
    "non_ascii_folder": (1, NO_LOG),  # %-escaped URI, raw URI, plain path (a non-ASCII folder: its own test)
    "reentrant_logger_instantiates": (0, 'fmi2Instantiate: fmuGUID "{wrong}" is not this FMU\'s'),
    "reentrant_logger_frees_during_set_real": (3, "fmi2SetReal: ParameterError: invalid phi1_0 = nan rad"),
    "reentrant_logger_frees_during_illegal_call": (3, "fmi2DoStep: illegal call sequence: not allowed in state "
                                                      "Instantiated"),
    # a logger that frees the FMU state a call uses, on the call's debug line (ASan's session: no use after free)
    "logger_frees_the_state_during_serialized_size": (3, "fmi2SerializedFMUstateSize: the FMU state was freed (by "
                                                         "the host's logger) during this call, which used it"),
    "logger_frees_the_state_during_get_state": (3, "fmi2GetFMUstate: the FMU state was freed (by the host's logger) "
                                                   "during this call, which used it"),
    "logger_frees_the_state_during_set_state": (0, "back to the FMU state at t = 0.125 s"),
    "large_start_time_wrong_point": (3, "fmi2DoStep: currentCommunicationPoint = 1000000000.5 s is not the FMU's "
                                        "time 1000000000 s"),
    "large_start_time_steps": (0, NO_LOG),
    "tampered_state_payload": (3, "fmi2DeSerializeFMUstate: the state is malformed"),
    "tampered_state_wrong_type": (3, "fmi2DeSerializeFMUstate: the state is malformed"),
    "tampered_state_truncated": (3, "fmi2DeSerializeFMUstate: the state is malformed"),
    "tampered_state_truncated_header": (3, "fmi2DeSerializeFMUstate: the 100 bytes are not a serialized state of "
                                           "this FMU (no header)"),
    "state_of_another_instance_set": (3, "fmi2SetFMUstate: FMU state 0x"),
    "state_of_another_instance_free": (3, "fmi2FreeFMUstate: FMU state 0x"),
    "state_of_another_instance_size": (3, "fmi2SerializedFMUstateSize: FMU state 0x"),
}
# What the calls without an instance (no logger to use) say on stderr, one line each.
ORPHANS = ["fmi2Instantiate: functions is NULL", "fmi2Instantiate: functions->logger is NULL",
           "fmi2DoStep: the instance is NULL", "fmi2SetReal: the instance is NULL",
           "fmi2DoStep: 0x", "is not a live instance of this FMU (freed, or never instantiated here)",
           "fmi2FreeInstance: 0x"]

FMI3_PROBES = {
    "exit_in_instantiated": (3, "fmi3ExitInitializationMode: illegal call sequence: not allowed in state Instantiated"),
    "exit_twice": (3, "fmi3ExitInitializationMode: illegal call sequence: not allowed in state Step Mode"),
    "do_step_before_initialisation": (3, "fmi3DoStep: illegal call sequence: not allowed in state Instantiated"),
    "terminate_twice": (3, "fmi3Terminate: illegal call sequence: not allowed in state Terminated"),
    "do_step_after_terminate": (3, "fmi3DoStep: illegal call sequence: not allowed in state Terminated"),
    "set_after_terminate": (3, "fmi3SetFloat64: illegal call sequence: not allowed in state Terminated"),
    "enter_step_mode_without_event_mode": (3, "fmi3EnterStepMode: illegal call sequence"),
    "model_exchange_function_in_co_simulation": (3, "fmi3SetTime: not a function of Co-Simulation"),
    "do_step_in_model_exchange": (3, "fmi3DoStep: not a function of Model Exchange"),
    "step_size_zero": (3, "fmi3DoStep: communicationStepSize = 0 s must be finite and > 0"),
    "step_size_nan": (3, "communicationStepSize = nan s"),
    "communication_point_not_the_fmus_time": (3, "currentCommunicationPoint = 2 s is not the FMU's time 0 s"),
    "do_step_null_out_argument": (3, "fmi3DoStep: eventHandlingNeeded is NULL"),
    "start_time_is_the_first_communication_point": (0, NO_LOG),
    "start_value_nan": (3, "fmi3SetFloat64: ParameterError: invalid phi1_0 = nan rad: must be finite"),
    "values_count_not_references_count": (3, "fmi3SetFloat64: nValues = 2, but 1 value references"),
    "get_float64_null_references": (3, "fmi3GetFloat64: valueReferences is NULL"),
    "get_float64_null_values": (3, "fmi3GetFloat64: values is NULL"),
    "get_float64_huge_count": (3, "fmi3GetFloat64: nValueReferences = 4611686018427387905, but this FMU has "),
    "set_float64_huge_count": (3, "fmi3SetFloat64: nValueReferences = 4611686018427387904, but this FMU has "),
    "get_boolean_huge_count": (3, "fmi3GetBoolean: nValueReferences = 4611686018427387905, but this FMU has "),
    "get_float32_not_a_type_of_this_fmu": (3, "fmi3GetFloat32: not supported by this FMU"),
    "get_clock": (3, "fmi3GetClock: not supported by this FMU (it has no clocks)"),
    "format_directives_in_a_string": (3, "invalid solver = '%s%s%n'"),
    "set_string_not_utf8": (3, ") is not UTF-8 (byte 3 is 0xe9; an fmi3String is UTF-8 encoded)"),
    "fixed_parameter_after_initialisation": (3, "cannot set parameter l1 = 0.5 after initialisation (FMI: a fixed "
                                                "parameter is set before the FMU leaves Initialization Mode)"),
    "wrong_token": (0, 'instantiationToken "{wrong}" is not this FMU\'s'),
    "null_token": (0, "instantiationToken NULL is not this FMU's"),
    "null_resource_path": (0, "resourcePath is NULL"),
    "null_instance_name": (0, "instanceName is NULL"),
    "instance_name_not_utf8": (0, "fmi3InstantiateCoSimulation: instanceName is not UTF-8 (byte 1 is 0xff"),
    "event_mode_requested": (0, "eventModeUsed = true, but this FMU has no Event Mode in Co-Simulation"),
    "scheduled_execution": (0, "offers Model Exchange and Co-Simulation only"),
    "null_logger_still_instantiates": (1, NO_LOG),  # FMI 3: the logger may be NULL
    "update_discrete_states_null_out_argument": (3, "fmi3UpdateDiscreteStates: terminateSimulation is NULL"),
    "set_continuous_states_wrong_count": (3, "nContinuousStates = 3, but this FMU has 13"),
    "get_continuous_states_null": (3, "continuousStates is NULL with nContinuousStates = 13"),
    "set_time_nan": (3, "fmi3SetTime: time = nan s must be finite"),
    "completed_integrator_step_null": (3, "fmi3CompletedIntegratorStep: enterEventMode is NULL"),
    "number_of_states": (0, NO_LOG),
    "get_fmu_state_null": (3, "fmi3GetFMUState: FMUState is NULL"),
    "set_fmu_state_foreign": (3, "is not a live state of this FMU"),
    "deserialize_garbage": (3, "are not a serialized state of this FMU"),
    "debug_logging_null_categories": (3, "fmi3SetDebugLogging: categories is NULL"),
    "configuration_mode_round_trip": (3, "fmi3EnterConfigurationMode: this FMU has no structural parameters"),
    "directional_derivative": (3, "providesDirectionalDerivatives = false"),
    "evaluate_discrete_states": (3, "fmi3EvaluateDiscreteStates: illegal call sequence: not allowed in state Step"),
    "null_instance": (3, NO_LOG),
    "error_state_then_reset": (0, "fmi3DoStep: illegal call sequence: not allowed in state Error"),
    "me_derivatives_in_initialization": (0, NO_LOG),  # OK, finite, equal (1e-12) to those after exit
    "me_set_continuous_states_nan": (3, "fmi3SetContinuousStates: continuousStates[3] = nan is not finite"),
    "me_huge_states_derivatives_discard": (2, "fmi3GetContinuousStateDerivatives: derivatives["),
    "tampered_state_interface": (3, "fmi3DeserializeFMUState: the bytes are a ModelExchange state; this instance is "
                                    "CoSimulation"),
}
# The probes' own words besides the fragments above.
PROBE_LINES = {
    "state_of_another_instance_set": "belongs to instance",
    "state_of_another_instance_free": "belongs to instance",
    "state_of_another_instance_size": "belongs to instance",
    "me_huge_states_derivatives_discard": "is not finite at these continuous states",
}


@pytest.fixture(scope="module")
def hosts(tmp_path_factory: pytest.TempPathFactory) -> dict[int, Path]:
    """The torture hosts by FMI version, compiled once for the session (host_binaries; sanitized with
    DOUBLE_PENDULUM_SANITIZE=1)."""
    return {version: compiled_host(tmp_path_factory, f"fmi{version}_torture") for version in (2, 3)}


@pytest.fixture(scope="module")
def extracted(fmu_path: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, object]]:
    """DoublePendulum (FMI 2 and FMI 3) and Suspension extracted, with their model descriptions."""
    from fmpy import extract, read_model_description

    folder = tmp_path_factory.mktemp("guarded")
    paths = {"fmi2": fmu_path, "suspension": fmu_path.parent / "Suspension.fmu",
             "fmi3": fmu_path.parent / "fmi3" / "DoublePendulum.fmu"}
    return {name: (Path(extract(str(path), str(folder / name))), read_model_description(str(path)))
            for name, path in paths.items()}


def host_command(host: Path, folder: Path, description, version: int, *mode: str) -> list[str]:
    names = ("phi1_0", "m1", "l1", "solver", "phi1", "pivot_ax", "air_drag", "fixed_step", "omega2_0")
    refs = {v.name: v.valueReference for v in description.modelVariables}
    identifier = (description.coSimulation or description.modelExchange).modelIdentifier
    token = description.guid if version == 2 else description.instantiationToken
    return [str(host), str(folder), identifier, token, *(f"{n}={refs[n]}" for n in names if n in refs), *mode]


def run(command: list[str], tmp_path: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run a host with a bare environment (what env -i PATH=/usr/bin:/bin gives it; and the sanitizers' options)."""
    return subprocess.run(command, capture_output=True, text=True, env=bare_environment(tmp_path), cwd=tmp_path,
                          timeout=timeout)


def bare_environment(home: Path) -> dict[str, str]:
    return {"PATH": "/usr/bin:/bin", "HOME": str(home), **sanitize.environment()}


def parse_probes(stdout: str) -> dict[str, tuple[int, list[tuple[int, str]]]]:
    probes: dict[str, tuple[int, list[tuple[int, str]]]] = {}
    name = None
    for line in stdout.splitlines():
        if line.startswith("probe "):
            _, name, status = line.split()
            probes[name] = (int(status), [])
        elif line.startswith("  log ") and name:
            status, _, text = line[6:].partition(" ")
            probes[name][1].append((int(status), text))
    return probes


def check_probes(probes: dict, expected: dict) -> None:
    assert set(probes) == set(expected), "every probe has its expectation, and every expectation ran"
    wrong = []
    for name, (status, fragment) in expected.items():
        got, logs = probes[name]
        if got != status:
            wrong.append(f"{name}: status {got}, expected {status} ({logs})")
        elif fragment == NO_LOG and logs:
            wrong.append(f"{name}: logged {logs}, expected nothing")
        elif fragment and not any(fragment in text for _, text in logs):
            wrong.append(f"{name}: no log line with {fragment!r} in {logs}")
        elif fragment and status == 3 and not any(level == 3 for level, _ in logs):
            wrong.append(f"{name}: its error was not logged with status fmi2Error/fmi3Error")
    assert not wrong, "\n".join(wrong)


@pytest.mark.skipif(not sanitize.ENABLED, reason=f"{sanitize.VARIABLE}=1 (scripts/check_memory.sh) builds them "
                                                   "sanitized")
def test_the_sanitized_session_runs_sanitized_loaders_and_hosts(hosts, extracted):
    """The memory check proves nothing unless its flags reached the builds: every loader and host links
    AddressSanitizer's and UndefinedBehaviorSanitizer's runtimes."""
    loaders = [folder / "binaries" / loader.PLATFORMS[3 if name == "fmi3" else 2]
               / f"{description.coSimulation.modelIdentifier}.so" for name, (folder, description) in extracted.items()]
    for path in [*loaders, *hosts.values()]:
        data = path.read_bytes()
        assert b"libasan.so" in data and b"libubsan.so" in data, f"{path} is not sanitized"


def check_probe_lines(probes: dict) -> None:
    for name, words in PROBE_LINES.items():
        if name in probes:
            assert any(words in text for _, text in probes[name][1]), (name, words, probes[name])


def test_every_fmi2_probe_gets_the_standards_answer_and_a_log_line(hosts, extracted, tmp_path):
    folder, description = extracted["fmi2"]
    done = run(host_command(hosts[2], folder, description, 2, "probes"), tmp_path)
    assert done.returncode == 0 and done.stdout.rstrip().endswith("end"), done.stdout[-3000:] + done.stderr
    check_probes(parse_probes(done.stdout), FMI2_PROBES)
    check_probe_lines(parse_probes(done.stdout))
    errors = done.stderr.splitlines()
    assert len(errors) == 6 and all(line.startswith("[DoublePendulum] ") for line in errors), errors
    for fragment in ORPHANS:
        assert any(fragment in line for line in errors), (fragment, errors)


def test_every_fmi3_probe_gets_the_standards_answer_and_a_log_line(hosts, extracted, tmp_path):
    folder, description = extracted["fmi3"]
    done = run(host_command(hosts[3], folder, description, 3, "probes"), tmp_path)
    assert done.returncode == 0 and done.stdout.rstrip().endswith("end"), done.stdout[-3000:] + done.stderr
    check_probes(parse_probes(done.stdout), FMI3_PROBES)
    check_probe_lines(parse_probes(done.stdout))
    assert done.stderr.splitlines() == ["[DoublePendulum] fmi3DoStep: the instance is NULL"]


@pytest.mark.slow
@pytest.mark.parametrize("version", [2, 3])
def test_sixteen_threads_instantiate_step_and_free_at_once(hosts, extracted, tmp_path, version):
    """16 threads at once, 3 rounds, in 8 processes (the first instantiations of a process start Python
    and import the bundle, where the races were): every instance created, every result bit-identical
    to the same case run alone."""
    folder, description = extracted[f"fmi{version}"]
    command = host_command(hosts[version], folder, description, version, "threads", "16", "3")
    processes = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                  env=bare_environment(tmp_path)) for _ in range(8)]
    for process in processes:
        out, err = process.communicate(timeout=300)
        assert process.returncode == 0, out + err
        assert "threads-created 48 of 48" in out and "threads-identical 1" in out, out + err


FORKS = 50


def test_forks_while_another_thread_steps_never_hang_the_child_in_a_c_host(hosts, extracted, tmp_path):
    """A C host (the loader starts the FMU's CPython itself) forks 50 times while another thread is inside
    fmi2DoStep: no child hangs (before the loader's fork handlers, 2 children of 2 waited for the dead thread's GIL
    forever) or crashes; in each, a new instance runs the case bit for bit as before the forks, and the instance the
    other thread was inside answers fmi2Error with the line that says why (or OK where the fork fell between two of
    its steps)."""
    folder, description = extracted["fmi2"]
    result = run(host_command(hosts[2], folder, description, 2, "fork", str(FORKS)), tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    counts = {key: int(value) for key, value in
              (line.split() for line in result.stdout.splitlines() if line.startswith("fork-"))}
    assert counts["fork-children"] == FORKS and counts["fork-hung"] == 0 and counts["fork-crashed"] == 0, counts
    assert counts["fork-identical"] == FORKS and counts["fork-bad"] == 0, counts
    assert counts["fork-refused"] > 0, f"no fork fell inside a step: the refusal was not exercised ({counts})"


FORKING_PYTHON_HOST = """
import os, signal, sys, threading, time
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
folder, guid, phi1, forks = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
def made():
    fmu = FMU2Slave(guid=guid, unzipDirectory=folder, modelIdentifier="DoublePendulum", instanceName="fork")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu
def case():
    fmu = made()
    for k in range(20):
        fmu.doStep(k * 0.01, 0.01)
    value = fmu.getReal([phi1])[0]
    fmu.terminate()
    fmu.freeInstance()
    return value
reference = case()
busy, inside, stop = made(), threading.Event(), threading.Event()
def keep_stepping():
    t = 0.0
    while not stop.is_set():
        inside.set()
        busy.doStep(t, 0.5)
        t += 0.5
thread = threading.Thread(target=keep_stepping)
thread.start()
hung = crashed = identical = refused = 0
for k in range(forks):
    inside.wait()
    time.sleep(0.001 * (k % 5))
    child = os.fork()
    if child == 0:
        code = 0
        try:  # refused where the fork fell inside a step, else the next step
            busy.doStep(busy.getRealStatus(2), 0.01)  # 2: fmi2LastSuccessfulTime
        except FMICallException as error:
            code |= 2 if error.status == 3 else 4
        code |= case() != reference
        os._exit(code)
    for _ in range(6000):
        ended, status = os.waitpid(child, os.WNOHANG)
        if ended:
            break
        time.sleep(0.01)
    else:
        os.kill(child, signal.SIGKILL)
        os.waitpid(child, 0)
        hung += 1
        continue
    code = os.waitstatus_to_exitcode(status)
    crashed += code < 0 or bool(code & 4)
    identical += code >= 0 and not code & 1
    refused += code >= 0 and bool(code & 2)
stop.set()
thread.join()
print("counts forks", forks, "hung", hung, "crashed", crashed, "identical", identical, "refused", refused)
"""


@in_this_process
def test_forks_while_another_thread_steps_never_hang_the_child_in_a_python_host(extracted, tmp_path):
    """The same in a Python host through fmpy (os.fork: the interpreter is the host's, its own fork handling runs,
    the loader's holds its locks and marks the busy instance): 50 forks, no child hangs or crashes, every new
    instance's case as before the forks, and the busy instance refused with fmi2Error where the fork fell inside
    its step, with the line that says so (printed by fmpy's logger)."""
    folder, description = extracted["fmi2"]
    phi1 = next(v.valueReference for v in description.modelVariables if v.name == "phi1")
    result = subprocess.run([sys.executable, "-c", FORKING_PYTHON_HOST, str(folder), description.guid, str(phi1),
                             str(FORKS)], capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    words = result.stdout.splitlines()[-1].split()[1:]  # before it, fmpy's logger prints the FMU's lines
    counts = dict(zip(words[::2], map(int, words[1::2])))
    assert counts == {**counts, "forks": FORKS, "hung": 0, "crashed": 0, "identical": FORKS}, counts
    assert counts["refused"] > 0, f"no fork fell inside a step: the refusal was not exercised ({counts})"
    assert "this process was forked while another thread was inside fmi2DoStep of this instance" in result.stdout


def rss_figures(stdout: str) -> dict[int, int]:
    """The host's "rss CYCLE KIB" lines: resident memory (KiB) by cycle."""
    return {int(k): int(kib) for _, k, kib in (line.split() for line in stdout.splitlines()
                                               if line.startswith("rss "))}


@pytest.fixture(scope="module")
def soak(hosts, extracted, tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[int, int], str]:
    """One soak of SOAK_CYCLES instantiate/initialise/step/free cycles in the C host (its own process, a
    bare environment), read by both soak tests: resident memory (KiB) every SOAK_EVERY cycles, and the
    host's stdout."""
    folder, description = extracted["fmi2"]
    command = host_command(hosts[2], folder, description, 2, "soak", str(SOAK_CYCLES), str(SOAK_EVERY))
    done = run(command, tmp_path_factory.mktemp("soak"))
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr
    return rss_figures(done.stdout), done.stdout


@pytest.mark.slow
def test_memory_stays_flat_over_thousands_of_instantiate_free_cycles(soak):
    """The first 2,000 of the soak's instantiate/initialise/step/free cycles in the C host (fixture soak):
    resident memory grows by less than 1 KiB per cycle over cycles 500 to 2,000 (before the guard: about
    70 KiB). Sanitized: 500 cycles, each call checked, and no slope (AddressSanitizer keeps freed memory in
    quarantine: resident memory grows about 200 KiB a cycle by design)."""
    rss, stdout = soak
    assert SOAK_CYCLES in rss, stdout[-2000:]
    if not sanitize.ENABLED:
        slope = (rss[2000] - rss[500]) / 1500
        assert slope < 1.0, f"{slope:.2f} KiB per cycle: {rss}"


@pytest.fixture(scope="module")
def foreign(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Another author's pythonfmu FMUs named DoublePendulum and Suspension, extracted."""
    from fmpy import extract

    folder = tmp_path_factory.mktemp("foreign")
    built = {model: build_foreign_fmu(folder, model) for model in ("DoublePendulum", "Suspension")}
    return {model: Path(extract(str(path), str(folder / f"{model}_x"))) for model, path in built.items()}


def test_a_foreign_fmu_of_the_same_names_beside_ours_in_a_c_host(hosts, extracted, foreign, tmp_path):
    """Ours, then another author's DoublePendulum (its own slave_common, double_pendulum, pythonfmu), then
    ours again: both run, and ours gives the same number. (In a C host the foreign FMU, pythonfmu's plain
    binary, needs a Python in the process: ours brings it. The CPython ours carries holds only the standard
    library ours needs, so beside a pythonfmu FMU ours is pointed at the machine's full CPython, as docs/fmu.md
    advises for such mixes.)"""
    from fmpy import read_model_description

    folder, description = extracted["fmi2"]
    theirs = foreign["DoublePendulum"]
    guid = read_model_description(str(theirs)).guid
    env = {**bare_environment(tmp_path), "DOUBLE_PENDULUM_FMU_PYTHON": getattr(sys, "_base_executable", sys.executable)}
    done = subprocess.run(host_command(hosts[2], folder, description, 2, "neighbour", str(theirs), "DoublePendulum",
                                       guid), capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "neighbour-ran 1" in done.stdout and "neighbour-identical 1" in done.stdout, done.stdout + done.stderr


NEIGHBOURS = textwrap.dedent("""
    import json, sys
    from fmpy import simulate_fmu
    order, ours, theirs = sys.argv[1], json.loads(sys.argv[2]), json.loads(sys.argv[3])
    out = {}
    def run_ours(tag):
        for name, path in ours.items():
            r = simulate_fmu(path, stop_time=0.2, output_interval=0.01, start_values=START[name])
            out[f"{tag} {name}"] = float(r[OUTPUT[name]][-1])
    def run_theirs(tag):
        for name, path in theirs.items():
            out[f"{tag} theirs {name}"] = float(simulate_fmu(path, stop_time=0.2, output_interval=0.01)["x"][-1])
    START = {"DoublePendulum": {"phi1_0": 1.3}, "Suspension": {"F_static_y": -20.0}}
    OUTPUT = {"DoublePendulum": "phi1", "Suspension": "y"}
    for step in order.split(","):
        (run_ours if step.startswith("ours") else run_theirs)(step)
    print(json.dumps(out))
""")


@in_this_process
def test_foreign_fmus_of_the_same_names_before_and_after_ours_in_fmpy(extracted, foreign, tmp_path):
    """In one fmpy process, another author's DoublePendulum and Suspension first, then ours, then theirs
    and ours again (and ours alone in a fresh process, for the reference): ours runs its own code and
    gives the same numbers whatever ran before; theirs run theirs."""
    import json

    ours = {"DoublePendulum": str(extracted["fmi2"][0]), "Suspension": str(extracted["suspension"][0])}
    theirs = {name: str(path) for name, path in foreign.items()}

    def run_order(order: str) -> dict:
        done = subprocess.run([sys.executable, "-c", NEIGHBOURS, order, json.dumps(ours), json.dumps(theirs)],
                              capture_output=True, text=True, cwd=tmp_path, timeout=300)
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
        return json.loads(done.stdout.strip().splitlines()[-1])

    alone = run_order("ours")
    mixed = run_order("theirs,ours1,theirs2,ours2")
    for name in ours:
        assert mixed[f"ours1 {name}"] == alone[f"ours {name}"] == mixed[f"ours2 {name}"]
        for tag in ("theirs", "theirs2"):
            assert mixed[f"{tag} theirs {name}"] == pytest.approx(START + RATE * 0.2)


@in_this_process
def test_python_threads_run_instances_at_once_in_fmpy(extracted):
    """8 Python threads at once, each its own fmpy instance (ctypes lets go of the GIL in every FMI call):
    every result bit-identical to the same case run alone."""
    from concurrent.futures import ThreadPoolExecutor

    from fmpy.fmi2 import FMU2Slave

    folder, description = extracted["fmi2"]
    refs = {v.name: v.valueReference for v in description.modelVariables}

    def case(start: float) -> float:
        fmu = FMU2Slave(guid=description.guid, unzipDirectory=str(folder), modelIdentifier="DoublePendulum",
                        instanceName=f"thread{start}")
        fmu.instantiate()
        fmu.setReal([refs["phi1_0"]], [start])
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        for k in range(20):
            fmu.doStep(currentCommunicationPoint=k * 0.01, communicationStepSize=0.01)
        phi1 = fmu.getReal([refs["phi1"]])[0]
        fmu.terminate()
        fmu.freeInstance()
        return phi1

    starts = [0.5 + 0.1 * k for k in range(8)] * 2
    with ThreadPoolExecutor(max_workers=8) as pool:
        parallel = list(pool.map(case, starts))
    assert parallel == [case(start) for start in starts]


# --------------------------------------------------------------------- what the FMU leaves to the host


def probe_info(stdout: str, name: str) -> list[str]:
    """The "  info" lines a probe printed after its "probe" line."""
    lines, inside = [], False
    for line in stdout.splitlines():
        if line.startswith("probe "):
            inside = line.split()[1] == name
        elif inside and line.startswith("  info "):
            lines.append(line[7:])
    return lines


def run_own(hosts, version: int, folder: Path, description, tmp_path: Path, name: str, env: dict | None = None,
            options: tuple[str, ...] = (), timeout: float = 120) -> tuple[int, list, list[str], str]:
    """One probe in a process of its own (its first instantiation), with a bare environment plus `env`:
    its status, log lines, info lines and the host's stderr."""
    command = host_command(hosts[version], folder, description, version, *options, "probes", name)
    done = subprocess.run(command, capture_output=True, text=True, cwd=tmp_path, timeout=timeout,
                          env={**bare_environment(tmp_path), **(env or {})})
    assert done.returncode == 0 and done.stdout.rstrip().endswith("end"), done.stdout[-3000:] + done.stderr[-3000:]
    status, logs = parse_probes(done.stdout)[name]
    return status, logs, probe_info(done.stdout, name), done.stderr


@pytest.mark.parametrize("name", ["locale_unchanged", "host_state_unchanged", "stdio_unlocked_after_instantiate"])
def test_the_first_instantiation_leaves_locale_signals_environment_and_stdio_as_the_host_had_them(
        hosts, extracted, tmp_path, name):
    """A C host that never called setlocale, started with LANG=C.UTF-8 (LC_ALL unset): its first
    instantiation (Python started in it) leaves setlocale(LC_ALL, NULL) "C"; the environment, the
    dispositions of SIGINT, SIGTERM (the host's own handlers), SIGPIPE, SIGCHLD, SIGXFSZ, SIGSEGV and the
    signal mask are unchanged after instantiation and after free; another thread gets stderr's and
    stdout's locks right after fmi2Instantiate returns."""
    folder, description = extracted["fmi2"]
    status, logs, info, _ = run_own(hosts, 2, folder, description, tmp_path, name, {"LANG": "C.UTF-8"})
    assert (status, logs) == (0, []), (status, logs, info)
    if name == "locale_unchanged":
        assert info == ["LANG=C.UTF-8 LC_ALL=(unset) locale before=C after-instantiate=C after-free=C"], info


def test_another_thread_writes_to_stderr_while_the_first_instantiation_runs(hosts, extracted, tmp_path):
    """A thread writes a line with its time to stderr every 0.5 ms while the process's first fmi2Instantiate
    runs (it starts Python, which holds stderr's lock only while the interpreter starts): the longest gap
    between its lines is well under the instantiation's time (half of it at most; measured in 11 runs: gaps of
    5 to 16 ms in instantiations of 54 to 161 ms, at most 0.18 of it)."""
    folder, description = extracted["fmi2"]
    status, logs, info, stderr = run_own(hosts, 2, folder, description, tmp_path,
                                         "stderr_writable_while_instantiating", {"LANG": "C.UTF-8"})
    assert (status, logs) == (0, []), (status, logs, info)
    words = info[0].split()
    gap, instantiation, writes = float(words[1]), float(words[3]), int(words[5])
    print(f"longest stderr gap {gap:.1f} ms while instantiating for {instantiation:.1f} ms ({writes} lines)")
    assert gap < 0.5 * instantiation, info
    assert stderr.count("stderr-writer") >= writes


@pytest.mark.parametrize("locale", [{"LC_ALL": "C"}, {"LANG": "C.UTF-8"}], ids=["C-locale", "C.UTF-8"])
def test_an_fmu_in_a_folder_with_a_non_ascii_name(hosts, extracted, tmp_path, locale):
    """The extracted FMU copied under a folder named "Ünï dir" (UTF-8): its resources named as a %-escaped
    file URI, a file URI with the raw bytes and a plain path all instantiate and step, in a C-locale host
    (LANG unset, LC_ALL=C) and with LANG=C.UTF-8."""
    import shutil

    folder, description = extracted["fmi2"]
    copy = tmp_path / "Ünï dir" / "DoublePendulum"
    shutil.copytree(folder, copy)
    status, logs, info, stderr = run_own(hosts, 2, copy, description, tmp_path, "non_ascii_folder", locale)
    assert (status, logs) == (1, []), (status, logs, info, stderr)
    assert "%C3%9Cn%C3%AF%20dir" in info[0] and ": 0; raw" in info[0] and "plain path: 0" in info[0], info


@pytest.mark.parametrize("name, other", [("foreign_resources", "(Suspension"),
                                         ("foreign_resources_reverse", "(DoublePendulum")])
def test_the_resources_of_the_other_fmu_are_refused_by_name(hosts, extracted, tmp_path, name, other):
    """DoublePendulum's binary and GUID with Suspension's resources folder, and Suspension's binary and
    GUID with DoublePendulum's: NULL, with a line that names the FMU whose resources they are."""
    folder, description = extracted["fmi2"]
    suspension, suspension_description = extracted["suspension"]
    options = (f"other_dir={suspension}", "other_id=Suspension", f"other_guid={suspension_description.guid}")
    status, logs, _, _ = run_own(hosts, 2, folder, description, tmp_path, name, options=options)
    assert status == 0, logs
    assert [level for level, _ in logs] == [3], logs
    assert f"is the resources folder of another FMU {other}" in logs[0][1], logs


def test_model_exchange_derivatives_twice_in_instantiated_never_crash(hosts, extracted, tmp_path):
    """The call that crashed the host before: the first is illegal in Instantiated (fmi3Error and a line); the
    second runs in the Error state, where FMI 3.0.2 (2.3.1: as in Terminated) lets a host read the state vectors
    for debugging: those of the start values, finite, fmi3OK. Nothing reaches the host's stderr."""
    folder, description = extracted["fmi3"]
    status, logs, info, stderr = run_own(hosts, 3, folder, description, tmp_path,
                                         "me_derivatives_twice_in_instantiated")
    assert "Traceback" not in stderr
    assert status == 0, (status, logs, info)
    assert [level for level, _ in logs] == [3], logs
    assert "not allowed in state Instantiated" in logs[0][1], logs


not_sanitized = pytest.mark.skipif(sanitize.ENABLED, reason="AddressSanitizer keeps freed memory: resident memory "
                                   "measures nothing of the FMU there")


@pytest.mark.slow
@not_sanitized
def test_four_thousand_instantiate_free_cycles_cost_no_memory_after_warm_up(soak):
    """The soak's 4,000 instantiate/initialise/step/free cycles (fixture soak): resident memory grows by less
    than 0.2 KiB a cycle over the 3,000 after a warm-up of 1,000. Measured every 100 cycles (three runs of
    6,000, 2026-12-05): the warm-up ends by cycle 500, then one step of the allocator, about 204 KiB (51 pages)
    near cycle 2,000, and not a page more up to cycle 6,000: 0.068 KiB a cycle over cycles 1,000-4,000
    (earlier over cycles 2,000-10,000: 0). The window takes two such steps (0.136, where 4,200 cycles took
    four); a leak at the limit still grows 600 KiB, 150 pages, over the 3,000; the defect the guard removed
    leaked 70 KiB a cycle. 4,000 where there were 6,000 and, before,
    10,000 (one of the suite's longest tests)."""
    rss, _ = soak
    slope = (rss[4000] - rss[1000]) / 3000
    print(f"C host soak: {slope:.3f} KiB per cycle over cycles 1000-4000 ({rss[1000]} -> {rss[4000]} KiB)")
    assert slope < 0.2, rss


@pytest.mark.slow
@not_sanitized
def test_dlopen_instantiate_free_dlclose_cycles_are_flat_after_warm_up(hosts, extracted, tmp_path):
    """3,000 cycles of dlopen, fmi2Instantiate, fmi2FreeInstance, dlclose of the binary (no other handle on
    it): the growth per cycle, the median over the 18 windows of 100 cycles from cycle 1,200 on, is less than
    0.5 KiB (the FMU before: 18 KiB a cycle; a window resolves 4 KiB / 100 = 0.04 KiB a cycle). The first
    cycles grow by up to 2 KiB a cycle, with the library kept loaded about as much (CPython's allocator warming
    up): measured every 100 cycles (two runs of 6,000, 2026-12-05) 2.2 in the first 300, 0.3 to 0.8 up to
    cycle 1,000; and the allocator takes a step of a few hundred KiB now and then (216 KiB near cycle 2,100),
    which the median leaves out; between them, quiet, 0.12 to 0.16 KiB a cycle, steady (earlier: 0.14 to 0.15
    over 300-cycle windows, 10,000 cycles, two runs), a residue of loading the binary again that the cycles
    with the library kept do not show. Should the warm-up last longer elsewhere, half the windows may still
    be in it before the median notices. 3,000 where there were 6,000 (one of the suite's longest tests)."""
    folder, description = extracted["fmi2"]
    done = run(host_command(hosts[2], folder, description, 2, "reload", "3000", "100"), tmp_path)
    assert done.returncode == 0 and "reload-failed" not in done.stdout, done.stdout[-2000:] + done.stderr
    rss = rss_figures(done.stdout)
    cycles = sorted(k for k in rss if k >= 1200)
    assert len(cycles) == 19, rss
    slopes = sorted((rss[b] - rss[a]) / (b - a) for a, b in zip(cycles, cycles[1:]))
    median = slopes[len(slopes) // 2]
    print(f"dlopen/dlclose cycles: median {median:.2f} KiB per cycle over {len(slopes)} windows from cycle "
          f"{cycles[0]} on ({rss[cycles[0]]} -> {rss[cycles[-1]]} KiB)")
    assert median < 0.5, rss
