"""How a sweep is cut into tasks: points that share one model (the swept constant is read
by the properties only) are grouped into chunks checked on one build; other constants get
one task per value; step bounds go in chunks."""

from __future__ import annotations

from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.reports.sweep_tasks import Task, independent, make_tasks, model_text
from afsmc.verify.reports.sweep_values import Kind

# D is read by a property only; P_FAIL by the model.
MODEL = """
machine deadline;
param int D = 5;
param prob P_FAIL = 0.2;
var t : [0..20] init 0 clamp;
var left : [0..2] init 2;
mode Work = 0 initial;
mode Done = 1 final;
action Step in Work when left > 0 {
    1 - P_FAIL: left -= 1, t += 2;
    P_FAIL: t += 2;
}
action Finish in Work when left == 0 {
    goto Done;
}
label done = mode == Done;
property by_deadline = P=? [ F "done" && t <= D ];
"""

# K is read by the model between the ends of the sweep only: [0..1], [0..2], [0..1].
MIDDLE = """
machine middle;
param int K = 0;
var x : [0..1 + K * (2 - K)] init 0;
mode A = 0 initial;
mode B = 1 final;
action Go in A { goto B; }
label done = mode == B;
property p = P=? [ F "done" ];
"""

# D is read by labels only, directly and through a formula no action reads; EARLY by a label
# that an action's guard reads through a formula (labels: properties only; formulas: both).
LABELS = """
machine labels;
param int D = 5;
param int EARLY = 1;
var t : [0..20] init 0 clamp;
mode Work = 0 initial;
mode Done = 1 final;
formula late = t > D;
formula busy = t < EARLY;
action Step in Work when t < 6 { t += 2; }
action Finish in Work when t >= 6 || busy { goto Done; }
label on_time = mode == Done && !late;
label early = mode == Done && t <= D - 2;
label quick = mode == Done && busy;
property by_deadline = P=? [ F "on_time" ];
property early = P=? [ F "early" ];
property quick = P=? [ F "quick" ];
"""

def _base(variable: str, kind: Kind = "const") -> Task:
    return Task(path="m.afsm", text=MODEL, consts=(), properties=(), formulas=(),
                variable=variable, kind=kind, xs=(), options=VerifyOptions())


def test_a_constant_only_the_properties_read_leaves_the_model_unchanged() -> None:
    assert independent("m.afsm", MODEL, {}, "D", [0, 3, 7, 20])


def test_a_constant_the_model_reads_changes_it() -> None:
    assert not independent("m.afsm", MODEL, {}, "P_FAIL", [0.1, 0.2])


def test_every_value_is_compared_not_only_the_ends() -> None:
    assert not independent("m.afsm", MIDDLE, {}, "K", [0, 1, 2])
    assert independent("m.afsm", MIDDLE, {}, "K", [0, 2])


def test_a_single_value_is_not_shared() -> None:
    assert not independent("m.afsm", MODEL, {}, "D", [5])


def test_points_that_share_a_model_go_in_one_chunk_per_job() -> None:
    values = [0, 2, 4, 6, 8]
    tasks = make_tasks(_base("D"), values, jobs=2, dask=None, progress=None)
    assert [t.xs for t in tasks] == [(0, 2, 4), (6, 8)]
    # each chunk knows the whole sweep, so that every chunk builds the same model
    assert all(t.shared and t.sweep_xs == tuple(values) for t in tasks)
    one = make_tasks(_base("D"), values, jobs=1, dask=None, progress=None)
    assert [t.xs for t in one] == [tuple(values)] and one[0].shared


def test_a_constant_the_model_reads_gets_one_task_per_value() -> None:
    tasks = make_tasks(_base("P_FAIL"), [0.1, 0.2, 0.3], jobs=2, dask=None, progress=None)
    assert [t.xs for t in tasks] == [(0.1,), (0.2,), (0.3,)]
    assert not any(t.shared for t in tasks)


def test_step_bounds_go_in_chunks() -> None:
    bounds = list(range(10))
    local = make_tasks(_base("bound", "bound"), bounds, jobs=3, dask=None, progress=None)
    assert [t.xs for t in local] == [(0, 1, 2, 3), (4, 5, 6, 7), (8, 9)]
    # on Dask, four chunks per job
    dask = make_tasks(_base("bound", "bound"), bounds, jobs=2, dask="tcp://x:1",
                      progress=None)
    assert [len(t.xs) for t in dask] == [2, 2, 2, 2, 2]


def test_many_values_say_that_the_model_is_compared_first() -> None:
    said: list[str] = []
    make_tasks(_base("D"), list(range(101)), jobs=1, dask=None, progress=said.append)
    assert said == ["sweep: comparing the model at the 101 values of D"]


def test_a_constant_only_labels_read_leaves_the_model_unchanged() -> None:
    """Labels are state predicates that only properties read: a shared sweep writes them
    out in each point's properties, so the model it builds has no use for them."""
    assert independent("m.afsm", LABELS, {}, "D", [0, 3, 7, 20])


def test_a_constant_a_guard_reads_through_a_formula_changes_the_model() -> None:
    assert not independent("m.afsm", LABELS, {}, "EARLY", [0, 1, 2])


def test_the_model_text_keeps_what_the_model_reads_and_drops_what_only_labels_read() -> None:
    text = model_text("m.afsm", LABELS, {"D": "3"})
    assert 'label "on_time"' not in text and 'label "early"' not in text
    assert "formula late" not in text and "const int D" not in text
    # `quick` reads E through a formula the model reads too: written out in the properties,
    # its declaration goes; the formula and EARLY stay
    assert 'label "quick"' not in text
    assert "formula busy" in text and "const int EARLY = 1;" in text
