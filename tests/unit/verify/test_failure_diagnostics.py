"""afsmc.verify.engines.failures: each way a Storm process fails becomes one afsmc diagnostic
(E402-E406, E411), pointing at the .afsm source where it can; and a failed query is told
from a failed model."""

from __future__ import annotations

from afsmc.compiler import lowered
from afsmc.diagnostics import Diagnostic, Severity
from afsmc.lower.lowering import Lowered
from afsmc.model import ir
from afsmc.verify.engines.failures import failure_diagnostic, one_query
from afsmc.verify.engines.jobs import make_job
from afsmc.verify.engines.storm import Engine, Job, JobResult, Stage, StormFailure
from afsmc.verify.plan.queries import TERMINATES
from tests.unit.verify.models import TEXT, prop, tiny


def _setup(engine: Engine = "sparse") -> tuple[ir.Model, Lowered, Job]:
    model = tiny()
    low = lowered(model, "nondet")
    return model, low, make_job(low, model.properties, "prism", engine, 1000, "MDP")


def _diagnose(stage: Stage, message: str, prop_name: str | None = None,
              line: int | None = None, engine: Engine = "sparse") -> Diagnostic:
    model, low, job = _setup(engine)
    return failure_diagnostic(StormFailure(stage, message, prop_name, line), model, low,
                              model.properties, job)


def _line_of(source: str, text: str) -> int:
    """The 1-based line of `text` in `source`."""
    return source[:source.index(text)].count("\n") + 1


def test_too_big_is_e405_with_the_max_states_hint() -> None:
    d = _diagnose("too-big", "the MDP has more than 1,000 states")
    assert (d.code, d.severity, d.message) == (
        "E405", Severity.ERROR, "the MDP has more than 1,000 states; the largest ranges: x (9 "
        "values), 3 modes")  # what makes the model large
    assert d.hint == ("raise --max-states if the machine has the memory (the sparse engine "
                      "needs about 250 bytes per state), or check a smaller instance with "
                      "--const")


def test_out_of_memory_is_e406_and_the_hint_depends_on_the_engine() -> None:
    sparse = _diagnose("memory", "out of memory after 10 s")
    assert sparse.code == "E406"
    assert sparse.hint is not None and "--engine hybrid" in sparse.hint
    hybrid = _diagnose("memory", "out of memory after 10 s", engine="hybrid")
    assert hybrid.code == "E406"
    assert hybrid.hint is not None and "even symbolically" in hybrid.hint


def test_a_property_storm_cannot_read_is_e402_at_the_property() -> None:
    d = _diagnose("property", "unexpected token\n   ^", "done_min")
    assert d.code == "E402"
    assert d.message == "Storm cannot check property 'done': unexpected token"
    assert d.span == prop(tiny(), "done").span


def test_a_failed_check_is_e404_naming_the_model() -> None:
    d = _diagnose("check", "no result", "far_max")
    assert d.code == "E404"
    assert d.message == "Storm failed to check 'far' on the MDP: no result"
    assert d.hint is None  # the sparse engine has no engine to suggest


def test_a_failed_build_is_e403_at_the_variable_it_names() -> None:
    d = _diagnose("build", "variable x out of range")
    assert d.code == "E403"
    assert d.message == "Storm cannot build the MDP: variable x out of range"
    assert d.span is not None and TEXT[d.span.start:d.span.end].startswith("var x")


def test_a_parse_error_is_e411_at_the_afsm_line_the_prism_line_came_from() -> None:
    model, low, job = _setup()
    line = _line_of(job.model_text, 'label "done"')  # its comment names tiny.afsm:11
    d = failure_diagnostic(StormFailure("parse", "bad token", None, line), model, low,
                           model.properties, job)
    assert d.code == "E411"
    assert d.message == "Storm cannot read the generated PRISM model: bad token"
    assert d.span is not None and TEXT[d.span.start:d.span.end].startswith("label done")


def test_anything_else_is_an_internal_error() -> None:
    d = _diagnose("internal", "")
    assert (d.code, d.message) == ("E406", "internal error while running Storm: no message")


def test_a_failed_check_is_one_query_and_a_failed_build_is_the_model() -> None:
    def failed(stage: Stage, prop_name: str | None = None, states: int = 0) -> bool:
        return one_query(JobResult(states=states, failure=StormFailure(stage, "", prop_name)))

    assert failed("check", "far_max")
    assert failed("property", "far_max")
    assert not failed("build")
    assert not failed("too-big")
    assert not failed("memory")  # before the model was built
    assert failed("memory", "far_max", states=100)  # after: the other queries may go on
    assert not failed("check", TERMINATES)  # every Pmax depends on it
