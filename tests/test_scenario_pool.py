"""``run all`` in child processes: order, groups, relayed lines, progress, failures, Ctrl-C."""

from __future__ import annotations

import io
import re
import sys
from pathlib import Path

import pytest
from double_pendulum.scenarios import EXPECTED_CPU_S, EXPECTED_QUICK_CPU_S, READS_FITS_OF, SCENARIOS

from double_pendulum.cli import main
from double_pendulum.runs import lines as scenario_lines
from double_pendulum.runs import pool as scenario_pool
from double_pendulum.runs import progress
from double_pendulum.runs.pool import Costs
from double_pendulum.runs.progress import ENV
from double_pendulum.runs.workers import WORKERS_ENV

COSTS = Costs(EXPECTED_CPU_S, EXPECTED_QUICK_CPU_S, READS_FITS_OF)
"""The scenarios' own costs, as the command line gives them to the pool."""


def test_every_scenario_has_an_expected_cost_and_the_longest_start_first():
    assert set(EXPECTED_CPU_S) == set(SCENARIOS)
    assert set(EXPECTED_QUICK_CPU_S) == set(SCENARIOS)
    order = scenario_pool.longest_first(SCENARIOS, COSTS)
    costs = [EXPECTED_CPU_S[name] for name in order]
    assert costs == sorted(costs, reverse=True)
    assert sorted(order) == sorted(SCENARIOS)


def test_a_default_run_gives_each_scenario_a_child_the_small_ones_a_few_the_largest_first():
    groups = scenario_pool.scenario_groups(SCENARIOS, COSTS, quick=False, jobs=2)
    order = scenario_pool.longest_first(SCENARIOS, COSTS)
    small = [name for name in order if EXPECTED_CPU_S[name] < scenario_pool.SMALL_SCENARIO_CPU_S]
    assert 1 < len(small) < len(SCENARIOS)
    singles = [group for group in groups if not set(group) & set(small)]
    assert sorted(singles) == sorted([[name] for name in order if name not in small])
    shared = [group for group in groups if set(group) & set(small)]
    assert sorted(name for group in shared for name in group) == sorted(small)
    assert all(sum(EXPECTED_CPU_S[name] for name in group) <= scenario_pool.SMALL_GROUP_CPU_S for group in shared)
    assert len(shared) < len(small)  # they do share
    totals = [sum(EXPECTED_CPU_S[name] for name in group) for group in groups]
    assert totals == sorted(totals, reverse=True)


def test_a_thorough_run_keeps_a_scenario_that_reads_cached_fits_after_the_one_that_writes_them():
    thorough = scenario_pool.scenario_groups(SCENARIOS, COSTS, quick=False, jobs=2, thorough=True)
    host = next(group for group in thorough if "loss_identification" in group)
    assert host == ["loss_identification", "measured_vs_sim"]  # the half fits of the motion test, from the cache
    assert thorough[0] == host  # the longest chain starts first
    assert sorted(n for g in thorough for n in g) == sorted(SCENARIOS)
    costs = Costs({"writer": 100.0, "reader": 5.0, "a": 50.0}, {}, {"reader": "writer", "absent": "gone"})
    assert scenario_pool.scenario_groups(["reader", "a"], costs, quick=False, jobs=2, thorough=True) == [
        ["a"], ["reader"]]  # the writer not in this run: the reader runs as in a default run


def test_default_run_groups_sort_by_their_sum_and_keep_the_packing_order():
    costs = {"a": 100.0, "b": 10.0, "cosimulation": 5.0, "c": 20.0, "d": 30.0}
    assert scenario_pool.scenario_groups(list(costs), Costs(costs, {}), quick=False, jobs=2) == [
        ["a"], ["c", "b", "cosimulation"], ["d"]]  # the small ones' 35 s before d's 30 s, longest first


def test_small_scenarios_are_packed_first_fit_under_the_cap():
    costs = {"a": 29.0, "b": 18.0, "c": 11.0, "d": 5.0, "e": 2.5, "f": 50.0}
    assert scenario_pool.pack_small(["f", "a", "b", "c", "d", "e"], Costs(costs, {}), cap=40.0) == [
        ["f"], ["a", "c"], ["b", "d", "e"]]  # f over the cap alone; a + b would be 47 s


def test_a_quick_run_shares_the_scenarios_out_longest_first_to_the_least_loaded():
    costs = {"a": 5.0, "b": 4.0, "c": 3.0, "d": 3.0, "e": 2.0, "cosimulation": 1.0, "f": 0.5}
    # a 5 | b 4 | c -> b 7 | d -> a 8 | e -> b 9 | cosimulation -> a 9 | f -> a 9.5 (the first of the least)
    assert scenario_pool.scenario_groups(list(costs), Costs({}, costs), quick=True, jobs=2) == [
        ["a", "d", "cosimulation", "f"],  # 9.5, in the order they joined: no scenario needs to run first
        ["b", "c", "e"],  # 9
    ]


def test_a_quick_run_keeps_a_scenario_that_reads_a_cached_fit_after_the_one_that_writes_it():
    for jobs in (1, 2, 3, 4):  # the real pair: measured_vs_sim reads loss_identification's fit
        host = next(group for group in scenario_pool.scenario_groups(SCENARIOS, COSTS, quick=True, jobs=jobs)
                    if "loss_identification" in group)
        assert host.index("measured_vs_sim") > host.index("loss_identification")
    costs = Costs({}, {"a": 5.0, "writer": 4.0, "b": 3.5, "reader": 3.0, "cosimulation": 1.0}, {"reader": "writer"})
    # alone the reader would join a (a 5 | writer 4 | b -> 7.5 | reader -> a 8); as a unit: writer + reader 7 | a 5
    # | b -> a 8.5 | cosimulation -> 8
    assert scenario_pool.scenario_groups(list(costs.quick), costs, quick=True, jobs=2) == [
        ["a", "b"], ["writer", "reader", "cosimulation"]]
    assert scenario_pool.scenario_groups(["a", "reader", "cosimulation"], costs, quick=True, jobs=2) == [
        ["a"], ["reader", "cosimulation"]]  # without its writer the reader is placed alone


@pytest.mark.parametrize("jobs", [1, 2, 3, 4, 11, 20])
def test_quick_groups_hold_every_scenario_once_and_balanced(jobs):
    groups = scenario_pool.scenario_groups(SCENARIOS, COSTS, quick=True, jobs=jobs)
    assert len(groups) == min(jobs, len(SCENARIOS))
    assert sorted(name for group in groups for name in group) == sorted(SCENARIOS)
    assert all(group for group in groups)
    totals = [sum(EXPECTED_QUICK_CPU_S[name] for name in group) for group in groups]
    assert totals == sorted(totals, reverse=True)  # the largest group starts first
    if len(groups) > 1:  # no group could give its last scenario to the smallest and be better off
        assert totals[0] - totals[-1] <= max(EXPECTED_QUICK_CPU_S.values())
    if jobs == 2:
        assert totals[0] - totals[1] < 1.0  # about equal halves of the measured costs


def test_a_child_command_names_its_scenarios_and_their_numbers_and_runs_them_in_its_process(tmp_path):
    command = scenario_pool.child_command(["cosimulation", "chaos"], ["1/11", "10/11"], tmp_path, tmp_path / "x.fmu",
                                          quick=True, thorough=False)  # fmt: skip
    run = command[command.index("run"):]
    assert run[:3] == ["run", "cosimulation", "chaos"]
    assert run[run.index("--index") + 1] == "1/11,10/11"
    assert run[run.index("--jobs") + 1] == "1"
    assert "--quick" in run and "--thorough" not in run


def test_the_lines_a_scenario_prints_are_read_back():
    names = ("chaos", "stability")
    assert scenario_lines.header_name(scenario_lines.header_line("3/11", "chaos", "sensitivity"), names) == "chaos"
    assert scenario_lines.header_name("  - chaos: a step", names) is None
    assert scenario_lines.header_name("[1/2] other: its header ...", names) is None
    wrote = scenario_lines.wrote_line("stability", Path("out/stability"), 1.0, 2.0)
    assert scenario_lines.outcome(wrote, names) == ("stability", scenario_lines.WROTE)
    failed = scenario_lines.failed_line("chaos", "boom")
    assert scenario_lines.outcome(failed, names) == ("chaos", scenario_lines.FAILED)
    assert scenario_lines.outcome("chaos: wrote nothing yet", ("stability",)) is None
    assert scenario_lines.outcome("chaos: writes", names) is None


def test_child_lines_are_marked_with_their_scenario():
    assert scenario_pool.marked("chaos", "  - flip map: 24 x 24 releases\n") == "  chaos: - flip map: 24 x 24 releases"
    assert scenario_pool.marked("chaos", "sweep (5 runs): 5/5 done") == "  chaos: sweep (5 runs): 5/5 done"
    # the child's own header and result lines already name it
    assert scenario_pool.marked("chaos", "[10/11] chaos: sensitivity ...\n") == "[10/11] chaos: sensitivity ..."
    assert scenario_pool.marked("chaos", "chaos: wrote results/chaos in 1 s") == "chaos: wrote results/chaos in 1 s"


@pytest.mark.parametrize(("parent", "child"), [("", "lines"), ("bar", "lines"), ("off", "off")])
def test_children_count_progress_in_plain_lines_unless_it_is_off(monkeypatch, parent, child):
    monkeypatch.setenv(ENV, parent)
    assert scenario_pool.child_environment()[ENV] == child


def test_children_run_their_sweeps_on_one_worker_unless_the_user_chose_a_number(monkeypatch):
    monkeypatch.delenv(WORKERS_ENV, raising=False)
    assert scenario_pool.child_environment()[WORKERS_ENV] == "1"
    assert scenario_pool.child_environment(2)[WORKERS_ENV] == "2"  # fewer children than cores
    monkeypatch.setenv(WORKERS_ENV, "3")
    assert scenario_pool.child_environment()[WORKERS_ENV] == "3"
    assert scenario_pool.child_environment(2)[WORKERS_ENV] == "3"


def test_lines_of_a_group_child_are_marked_with_the_scenario_running_in_it():
    child = scenario_pool.Child(("a", "b"), process=None, current="a")
    assert child.take("loading\n") == ("  a: loading", None)
    assert child.take("[2/5] b: the second ...\n") == ("[2/5] b: the second ...", None)
    assert child.take("a step\n") == ("  b: a step", None)
    # a's failure line, relayed from stderr after b's header: as it is, and a reported
    assert child.take("a: FAILED: boom\n") == ("a: FAILED: boom", "a")
    assert child.take("b: wrote out/b in 1 s\n") == ("b: wrote out/b in 1 s", "b")
    assert child.take("b: wrote it again\n") == ("b: wrote it again", None)  # reported once
    assert child.failures(0) == ["a"] and child.failures(1) == ["a"] and child.unreported() == []


def _fake_children(monkeypatch, scripts: dict[str, str]) -> None:
    """Children that run a small Python script, chosen by their first scenario's name, instead of the scenarios."""
    monkeypatch.setattr(scenario_pool, "child_command",
                        lambda names, *args: [sys.executable, "-c", scripts[names[0]]])  # fmt: skip


class _Bar:
    """A stand-in progress bar that records its total and each update."""

    def __init__(self, total: int) -> None:
        self.total, self.updates, self.n = total, [], 0

    def update(self, n: int) -> None:
        if n:
            self.updates.append(n)
        self.n += n

    def set_total(self, total: int) -> None:
        self.total = total

    def __enter__(self) -> _Bar:
        return self

    def __exit__(self, *exc: object) -> None:
        pass


def _recorded_bars(monkeypatch) -> list[_Bar]:
    """The progress bars run_in_children makes from now on, as :class:`_Bar`."""
    made: list[_Bar] = []

    def make(total, *args, **kwargs) -> _Bar:
        made.append(_Bar(total))
        return made[-1]

    monkeypatch.setattr(scenario_pool, "progress_bar", make)
    return made


def test_a_group_child_relays_its_scenarios_lines_marked_with_each(monkeypatch, tmp_path, capsys):
    script = ("print('[1/2] a: first ...'); print('working'); print('a: wrote x'); "
              "print('[2/2] b: second ...'); print('working'); print('b: wrote y')")  # fmt: skip
    _fake_children(monkeypatch, {"a": script})
    failed = scenario_pool.run_in_children(["a", "b"], tmp_path, tmp_path / "x.fmu", COSTS, quick=True,
                                           thorough=False, jobs=1)  # fmt: skip
    assert failed == []
    out = capsys.readouterr().out.splitlines()
    assert out == ["[1/2] a: first ...", "  a: working", "a: wrote x", "[2/2] b: second ...", "  b: working",
                   "b: wrote y"]  # fmt: skip


def test_a_group_child_that_dies_mid_group_fails_the_rest_and_the_bar_still_ends_full(monkeypatch, tmp_path,
                                                                                       capsys):  # fmt: skip
    bars = _recorded_bars(monkeypatch)
    _fake_children(monkeypatch, {"a": "import sys; print('[1/3] a: ...'); print('a: wrote x'); "
                                      "print('[2/3] b: ...'); sys.exit(3)"})  # fmt: skip
    costs = Costs({}, {"a": 5.0, "b": 3.0, "c": 2.0})
    failed = scenario_pool.run_in_children(["c", "b", "a"], tmp_path, tmp_path / "x.fmu", costs, quick=True,
                                           thorough=False, jobs=1)  # fmt: skip
    assert failed == ["c", "b"]  # in the order of the names given
    err = capsys.readouterr().err
    assert "b: FAILED: its process ended with code 3" in err and "c: FAILED: its process ended with code 3" in err
    assert "a: FAILED" not in err
    assert bars[0].total == 10 and bars[0].n == 10  # full: a when it wrote, b and c when the child ended
    assert all(n > 0 for n in bars[0].updates)  # it never goes back


def test_failed_children_are_named_and_the_others_finish(monkeypatch, tmp_path, capsys):
    costs = Costs({"a": 300.0, "b": 200.0, "c": 100.0}, {})  # a child each
    _fake_children(monkeypatch, {
        "a": "print('working'); import sys; sys.exit(3)",
        "b": "import sys; print('b: FAILED: bad input', file=sys.stderr); sys.exit(1)",
        "c": "print('c: wrote it')",
    })  # fmt: skip
    failed = scenario_pool.run_in_children(["a", "b", "c"], tmp_path, tmp_path / "x.fmu", costs, quick=False,
                                           thorough=False, jobs=2)  # fmt: skip
    assert failed == ["a", "b"]
    out, err = capsys.readouterr()
    assert "  a: working" in out and "c: wrote it" in out
    assert "a: FAILED: its process ended with code 3" in err
    assert "b: FAILED: bad input" in err and "b: FAILED: its process" not in err  # the child said why


def test_ctrl_c_stops_every_child(monkeypatch, tmp_path):
    _fake_children(monkeypatch, {"a": "import time; time.sleep(60)", "b": "import time; time.sleep(60)"})
    started = []
    real_start = scenario_pool.start_child

    def start(*args):
        started.append(real_start(*args))
        return started[-1]

    def interrupt(seconds):
        raise KeyboardInterrupt

    monkeypatch.setattr(scenario_pool, "start_child", start)
    monkeypatch.setattr(scenario_pool, "_pause", interrupt)
    monkeypatch.setattr(scenario_pool, "STOP_GRACE_S", 0.2)
    with pytest.raises(KeyboardInterrupt):
        scenario_pool.run_in_children(["a", "b"], tmp_path, tmp_path / "x.fmu", COSTS, quick=True, thorough=False,
                                      jobs=2)
    assert len(started) == 2
    assert all(child.process.poll() is not None for child in started)  # none left running


def test_several_scenarios_in_children_write_every_folder(tmp_path, capsys, fmu_path):
    names = ["energy_decay", "friction_budget", "work_precision"]  # the three cheapest quick runs
    assert main(["run", *names, "--quick", "--jobs", "2", "--fmu", str(fmu_path), "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([*names, "index.html"])  # the page by the parent alone
    assert "3 scenarios in 2 processes" in out
    # one alone, the other two one after another in the other child: numbered 1 to 3 in the order they start
    headers = [line.split()[:2] for line in out.splitlines() if line.startswith("[")]
    assert [index for index, _ in headers] == ["[1/3]", "[2/3]", "[3/3]"]
    assert sorted(name.rstrip(":") for _, name in headers) == names
    assert out.count("scenarios wrote") == 1 and "3 of 3 scenarios wrote" in out  # the children's sums not shown


def test_jobs_below_one_is_refused_in_one_line(tmp_path, capsys):
    assert main(["run", "all", "--jobs", "0", "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err.strip() == "double-pendulum: error: --jobs must be at least 1, got 0"


def test_a_child_header_is_numbered_in_the_order_scenarios_start():
    starts = iter(["7/11", "8/11"])
    child = scenario_pool.Child(("a", "b"), process=None, current="a", number=lambda: next(starts))
    assert child.take("[1/11] a: first ...\n") == ("[7/11] a: first ...", None)
    assert child.take("a: wrote x\n") == ("a: wrote x", "a")
    assert child.take("[2/11] b: second ...\n") == ("[8/11] b: second ...", None)


def test_the_bar_credits_running_scenarios_with_their_time_so_far_where_their_cpu_time_is_unknown():
    weight = {"long": 100.0, "short": 10.0, "finished": 30.0}
    long_child = scenario_pool.Child(("long",), process=None, current="long", started=50.0)
    short_child = scenario_pool.Child(("short",), process=None, current="short", started=50.0)
    # 20 s into both: the long one has done 20 of its 100 s; the short one 20 s of its 10, so its share grows to
    # 20 / CREDIT_CAP and the whole with it
    work, whole = scenario_pool.progress_state(weight, {"finished": 30.0}, [long_child, short_child], now=70.0)
    assert work == 30 + 20 + 20 and whole == pytest.approx(30 + 100 + 20 / scenario_pool.CREDIT_CAP)
    # a reported scenario counts whole, not twice
    work, whole = scenario_pool.progress_state(weight, {"finished": 30.0, "short": 10.0}, [long_child, short_child],
                                               now=70.0)  # fmt: skip
    assert (work, whole) == (60, 140)


def test_under_load_the_bar_follows_the_work_done_and_its_time_left_stays_bounded(monkeypatch):
    """The run of issue 36 on a fake clock: chaos (expected 63 CPU s) and loss_identification (62) start side by
    side on a machine so loaded that each child gets a tenth of a core; chaos needs three times its expected CPU
    time, loss_identification's child goes on with the rest. The bar stood at 0.9 of the first two shares (112) for
    14 minutes while its time left grew; now it moves with the children's CPU time, and the time left that the
    plain-line counter prints never grows past its first estimate while work completes."""
    clock = [0.0]
    cpu = [0.0, 0.0]  # each child's CPU time [s]
    monkeypatch.setattr(progress.time, "monotonic", lambda: clock[0])
    weight = {"chaos": 63.0, "loss_identification": 62.0, "rest": 220.0}
    chaos = scenario_pool.Child(("chaos",), process=None, current="chaos", started=0.0, cpu=lambda: cpu[0])
    other = scenario_pool.Child(("loss_identification", "rest"), process=None, current="loss_identification",
                                started=0.0, cpu=lambda: cpu[1])  # fmt: skip
    lines = io.StringIO()
    counter = progress.LineProgress(round(sum(weight.values())), "11 scenarios", unit="CPU s", file=lines)
    done: dict[str, float] = {}
    works = []
    while "chaos" not in done:
        clock[0] += 10.0
        cpu[0], cpu[1] = cpu[0] + 1.0, cpu[1] + 1.0  # a tenth of a core each
        if other.current == "loss_identification" and other.work_done(clock[0]) >= 62.0:
            done["loss_identification"] = 62.0
            other.current, other.started, other.cpu_started = "rest", clock[0], cpu[1]
        if cpu[0] >= 3 * 63.0:
            done["chaos"] = 3 * 63.0 / scenario_pool.CREDIT_CAP
        work, whole = scenario_pool.progress_state(weight, done, [chaos, other], clock[0])
        counter.set_total(max(round(whole), counter.total))
        counter.update(max(0, int(work) - counter.n))
        works.append(work)
    assert all(later >= earlier for earlier, later in zip(works, works[1:]))
    assert works[-1] > 3 * 63 + 62  # far past where the old bar stood still (112)
    lefts = [_seconds(m) for m in re.findall(r"about (\S+) left", lines.getvalue())]
    assert len(lefts) >= 10
    assert max(lefts) <= lefts[0] and lefts[-1] < lefts[0] / 2  # the estimate does not run away while work is done


def _seconds(clock: str) -> float:
    """A progress line's m:ss or h:mm:ss [s]."""
    seconds = 0.0
    for part in clock.split(":"):
        seconds = 60 * seconds + float(part)
    return seconds
