"""The compiled kernels of the backward pass (afsmc.verify.kernels.passes) give the numpy
reference's values, optimal choices, self-loops and transition counts.

AFSMC_KERNELS=numba forces the kernels at any size, =numpy the reference; both run on the
same explored arrays (afsmc's own exploration of the UAV's small instance, a spec with
self-loops of several probabilities and a choice that only loops, and the rover). The
uniform DTMC's transitions are also counted by brute force: the distinct (state,
successor) pairs over each state's choices, as a set of Python tuples."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from afsmc.backends.prism import property_variants
from afsmc.compiler import load, lowered
from afsmc.verify.arrays import acyclic
from afsmc.verify.engines import explicit
from afsmc.verify.explorer import explore, explore_graph
from tests.conftest import EXAMPLES
from tests.unit.backends.test_prism import SMALL
from tests.unit.verify.test_uniform_beside import LOOPS

CLOSE = 1e-12


def _explored(path: str, consts: dict[str, str]) -> tuple[acyclic.Arrays, list[acyclic.Query]]:
    """The MDP's arrays from afsmc's exploration and every query of its properties: min
    and max, and the uniform DTMC's mean."""
    low = lowered(load(path, consts).model, "nondet")
    names = tuple(n for p in low.model.properties for n, _ in property_variants(low, p))
    p = explicit.plan(low, names)
    explicit.plan_uniform(low, tuple(prop.name for prop in low.model.properties), p)
    compiled = explore.compile_model(low, p.targets, p.rewards)
    return explore_graph.explore(compiled).arrays, p.queries


@pytest.fixture(scope="module", params=["uav", "loops", "rover"])
def model(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
          ) -> tuple[acyclic.Arrays, list[acyclic.Query]]:
    if request.param == "loops":
        path = tmp_path_factory.mktemp("loops") / "loops.afsm"
        path.write_text(LOOPS, encoding="utf-8")
        return _explored(str(path), {})
    return _explored(str(EXAMPLES / f"{request.param}.afsm"), SMALL.get(request.param, {}))


def _with(monkeypatch: pytest.MonkeyPatch, mode: str) -> None:
    monkeypatch.setenv("AFSMC_KERNELS", mode)


def test_the_model_has_what_the_kernels_must_handle(
        model: tuple[acyclic.Arrays, list[acyclic.Query]]) -> None:
    a, queries = model
    assert {q.opt for q in queries} >= {"min", "max", "mean"}
    assert len(np.unique(np.diff(a.states))) > 1 or np.diff(a.states).max() > 1  # choices


def test_the_values_of_every_query_equal_numpy_s(
        model: tuple[acyclic.Arrays, list[acyclic.Query]], monkeypatch: pytest.MonkeyPatch
        ) -> None:
    a, queries = model
    _with(monkeypatch, "numpy")
    reference = acyclic.solve_many(a, queries)
    _with(monkeypatch, "numba")
    compiled = acyclic.solve_many(a, queries)
    assert compiled.keys() == reference.keys()
    for name, v in reference.items():
        assert compiled[name] == pytest.approx(v, abs=CLOSE, rel=CLOSE), name
    assert any(0 < v < 1 for v in reference.values())


def test_a_plain_probability_array_gives_the_coded_one_s_values(
        model: tuple[acyclic.Arrays, list[acyclic.Query]], monkeypatch: pytest.MonkeyPatch
        ) -> None:
    # Storm's route gives the pass a float array, afsmc's exploration coded probabilities
    a, queries = model
    assert isinstance(a.prob, acyclic.Coded)
    plain = replace(a, prob=np.asarray(a.prob[0:len(a.prob)], np.float64))
    _with(monkeypatch, "numpy")
    reference = acyclic.solve_many(a, queries)
    _with(monkeypatch, "numba")
    got = acyclic.solve_many(plain, queries)
    for name, v in reference.items():
        assert got[name] == pytest.approx(v, abs=CLOSE, rel=CLOSE), name


def _schedulers(a: acyclic.Arrays, queries: list[acyclic.Query]
                ) -> tuple[list[float], np.ndarray, np.ndarray]:
    """Each query's value, every state's optimal choice and every state's value."""
    n = len(a.states) - 1
    best = np.zeros((n, len(queries)), np.int32)
    value = np.zeros((n, len(queries)))
    totals = []
    at = {q.name: j for j, q in enumerate(queries)}
    for part, got, chosen, values in acyclic.with_schedulers(a, queries):
        for j, q in enumerate(part):
            best[:, at[q.name]], value[:, at[q.name]] = chosen[:, j], values[:, j]
        totals += got
    return totals, best, value


def test_every_state_s_optimal_choice_and_value_equal_numpy_s(
        model: tuple[acyclic.Arrays, list[acyclic.Query]], monkeypatch: pytest.MonkeyPatch
        ) -> None:
    a, queries = model
    mine = [q for q in queries if q.opt != "mean"]
    _with(monkeypatch, "numpy")
    ref_totals, ref_best, ref_value = _schedulers(a, mine)
    _with(monkeypatch, "numba")
    totals, best, value = _schedulers(a, mine)
    assert totals == pytest.approx(ref_totals, abs=CLOSE, rel=CLOSE)
    np.testing.assert_array_equal(best, ref_best)
    np.testing.assert_allclose(value, ref_value, rtol=CLOSE, atol=CLOSE)
    # the maxima and minima choose differently somewhere: the choices are a real test
    assert (ref_best != 0).any()


def test_a_policy_s_values_equal_numpy_s(
        model: tuple[acyclic.Arrays, list[acyclic.Query]], monkeypatch: pytest.MonkeyPatch
        ) -> None:
    a, queries = model
    mine = [q for q in queries if q.opt != "mean" and q.kind == "P"]  # (a pass: one kind)
    _with(monkeypatch, "numpy")
    _, best, _ = _schedulers(a, mine)
    # every query under the scheduler of the last one (its max or min): not its own optimum
    plain = [replace(q, opt="") for q in mine]
    policy = acyclic.Policy(best, np.full(len(plain), len(plain) - 1, np.int64))
    reference = acyclic.evaluate(a, plain, policy)
    one = acyclic.under(a, plain[0], acyclic.Policy(best, np.array([0], np.int64)))
    _with(monkeypatch, "numba")
    assert acyclic.evaluate(a, plain, policy) == pytest.approx(reference, abs=CLOSE, rel=CLOSE)
    got = acyclic.under(a, plain[0], acyclic.Policy(best, np.array([0], np.int64)))
    assert got[0] == pytest.approx(one[0], abs=CLOSE, rel=CLOSE)
    np.testing.assert_array_equal(got[1], one[1])
    np.testing.assert_allclose(got[2], one[2], rtol=CLOSE, atol=CLOSE)


def _pairs(a: acyclic.Arrays) -> int:
    """Brute force: the distinct (state, successor) pairs over each state's choices."""
    seen = set()
    for s in range(len(a.states) - 1):
        for c in range(int(a.states[s]), int(a.states[s + 1])):
            for b in range(int(a.choices[c]), int(a.choices[c + 1])):
                seen.add((s, int(a.target[b])))
    return len(seen)


def test_the_uniform_dtmc_s_transitions_are_the_distinct_successors(
        model: tuple[acyclic.Arrays, list[acyclic.Query]], monkeypatch: pytest.MonkeyPatch,
        request: pytest.FixtureRequest) -> None:
    a, _ = model
    _with(monkeypatch, "numpy")
    reference = explicit._mean_transitions(a)
    _with(monkeypatch, "numba")
    assert explicit._mean_transitions(a) == reference == _pairs(a)
    # the UAV's floor/ceil choices share successors: there the pairs are fewer than the
    # branches, so counting them is a test (the rover's choices share none)
    assert reference < len(a.target) or "rover" in request.node.name


def test_the_self_loops_equal_numpy_s(
        model: tuple[acyclic.Arrays, list[acyclic.Query]], monkeypatch: pytest.MonkeyPatch
        ) -> None:
    a, _ = model
    _with(monkeypatch, "numpy")
    reference = acyclic.self_loops(a.states, a.choices, a.target, a.prob)
    _with(monkeypatch, "numba")
    got = acyclic.self_loops(a.states, a.choices, a.target, a.prob)
    assert (got is None) == (reference is None)
    if reference is not None and got is not None:
        assert type(got) is type(reference)
        m = len(a.choices) - 1
        np.testing.assert_array_equal(got[0:m], reference[0:m])


def _spans_settled(a: acyclic.Arrays, qs: list[acyclic.Query], with_best: bool,
                   with_picked: bool) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """acyclic.settle on each span of a pass (the streamed pass's use of it), from the
    choices' values of numpy's product: each span's states' values, and its optimal
    choices (with `with_best`)."""
    from scipy.sparse import csr_matrix

    n, k = len(a.states) - 1, len(qs)
    value = np.zeros((n, k))
    sense = acyclic.Sense.of(qs)
    labels = [a.labels[acyclic.LABEL + str(q.target)] for q in qs]
    rewards = [a.rewards[q.reward] for q in qs] if qs[0].kind == "R" else None
    values, bests = [], []
    for lo, hi in acyclic._spans(a.layers):
        c0, c1 = int(a.states[lo]), int(a.states[hi])
        b0, b1 = int(a.choices[c0]), int(a.choices[c1])
        matrix = csr_matrix((a.prob[b0:b1], a.target[b0:b1], a.choices[c0:c1 + 1] - b0),
                            shape=(c1 - c0, n))
        per_choice = np.asarray(matrix @ value)
        if rewards is not None:
            per_choice += np.stack([r[c0:c1] for r in rewards], axis=1)
        offsets = a.states[lo:hi + 1] - c0
        best = np.zeros((hi - lo, k), np.int32) if with_best else None
        # each state's last choice: another scheduler than the optimum
        picked = (np.repeat(np.diff(offsets)[:, None] - 1, k, axis=1).astype(np.int32)
                  if with_picked else None)
        got = acyclic.settle(per_choice, None if a.stay is None else a.stay[c0:c1], offsets,
                             np.stack([t[lo:hi] for t in labels], axis=1), sense, best, picked)
        value[lo:hi] = got
        values.append(got)
        bests.append(np.zeros(0) if best is None else best)
    return values, bests


@pytest.mark.parametrize("how", ["optimum", "best", "picked", "mean"])
def test_settle_equals_numpy_s(model: tuple[acyclic.Arrays, list[acyclic.Query]],
                               monkeypatch: pytest.MonkeyPatch, how: str) -> None:
    a, queries = model
    for kind in ("P", "R"):
        qs = [q for q in queries if q.kind == kind and (q.opt == "mean") == (how == "mean")]
        if how == "picked":
            qs = [replace(q, opt="") for q in qs]
        if not qs:
            continue
        _with(monkeypatch, "numpy")
        ref_values, ref_best = _spans_settled(a, qs, how == "best", how == "picked")
        _with(monkeypatch, "numba")
        values, best = _spans_settled(a, qs, how == "best", how == "picked")
        for got, ref in zip(values, ref_values, strict=True):
            np.testing.assert_allclose(got, ref, rtol=CLOSE, atol=CLOSE)
        for got, ref in zip(best, ref_best, strict=True):
            np.testing.assert_array_equal(got, ref)


@pytest.mark.parametrize("size", [1, 2, 7, 8, 9, 16, 17, 130, 300])
def test_a_state_of_many_choices_sums_as_numpy_does(monkeypatch: pytest.MonkeyPatch,
                                                     size: int) -> None:
    """The uniform DTMC's mean over `size` choices (with self-loops), on values of very
    different magnitudes, so that the order of the sum shows: numpy's add.reduceat sums
    pairwise from 9 terms on, the kernel the same way."""
    rng = np.random.default_rng(size)
    sizes = np.array([size, 1, size, 3])
    offsets = np.concatenate(([0], np.cumsum(sizes)))
    m = int(offsets[-1])
    per_choice = rng.random((m, 3)) * 10.0 ** rng.integers(-12, 12, (m, 3))
    stay = np.where(rng.random(m) < 0.5, rng.random(m) * 0.5, 0.0)
    on = np.zeros((len(sizes), 3), bool)
    qs = [acyclic.Query(str(j), "R", "mean", 0, "") for j in range(3)]
    sense = acyclic.Sense.of(qs)
    _with(monkeypatch, "numpy")
    reference = acyclic.settle(per_choice, stay, offsets, on, sense)
    _with(monkeypatch, "numba")
    np.testing.assert_array_equal(acyclic.settle(per_choice, stay, offsets, on, sense),
                                  reference)
