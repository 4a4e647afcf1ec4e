"""Continuous fuzzing of the command line (issue 36): whatever the file, `check`,
`compile` (PRISM, JANI, DOT) and `fmt` answer with an exit code of their own (0, 1 or 2,
never 3, an internal error), never print a traceback, and answer within a CPU limit per
command (tests/fuzz/harness.py).

The inputs: every file of tests/fuzz/corpus/ (inputs that once found a bug, and seeds),
then files drawn by hypothesis from the generators of tests/fuzz/generate.py: walks of the
grammar, whole machines whose names agree, mutations and splices of the examples, the
golden cases and the corpus, and seeds with a declaration drawn from the grammar; a few go
through a real `python -m afsmc` process as well.

Each generated test is bounded (AFSMC_FUZZ_EXAMPLES examples, default 40, and BUDGET
seconds of wall time) and derandomized, so CI runs the same inputs every time; the long
run with fresh inputs is benchmarks/fuzz.py. A failure prints the input and writes it to
a file to add to the corpus.
"""

from __future__ import annotations

import os
import random
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from tests.fuzz import generate, harness

EXAMPLES = int(os.environ.get("AFSMC_FUZZ_EXAMPLES", "40"))
BUDGET = 10.0  # seconds of wall time per generated test; the examples left are skipped
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
                suppress_health_check=list(HealthCheck))
CORPUS = sorted(generate.CORPUS.glob("*.afsm"))


@pytest.fixture(scope="module")
def workdir() -> Iterator[str]:
    with harness.workdir() as d:
        yield d


def _assert_sound(data: bytes, workdir: str, rng: random.Random | None = None) -> None:
    verdict = harness.judge(data, workdir, rng, compile_share=1.0 if rng is None else 0.3)
    if verdict.failures:
        fd, kept = tempfile.mkstemp(prefix="afsmc-fuzz-failure-", suffix=".afsm")
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        first = verdict.failures[0]
        pytest.fail(f"{first.kind} in `afsmc {' '.join(first.argv[:1] + first.argv[2:])}` "
                    f"on this input (kept in {kept}; add it to tests/fuzz/corpus/):\n"
                    f"{data!r}\n{first.detail}", pytrace=False)


def test_corpus_is_not_empty_and_not_excluded() -> None:
    assert len(CORPUS) >= 5
    for path in CORPUS:
        assert generate.excluded(path.read_bytes()) is None, path.name


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_corpus(path: Path, workdir: str) -> None:
    """Each kept input still gets an answer (every command, compile too)."""
    _assert_sound(path.read_bytes(), workdir)


def _budgeted(make: Callable[[random.Random], bytes]) -> Callable[[random.Random, str], None]:
    started: list[float] = []

    def body(rng: random.Random, workdir: str) -> None:
        if not started:
            started.append(time.monotonic())
        if time.monotonic() - started[0] > BUDGET:
            return  # the test's time is used up: the remaining examples pass unrun
        data = make(rng)
        assume(generate.excluded(data) is None)
        _assert_sound(data, workdir, rng)
    return body


_grammar = _budgeted(lambda rng: generate.from_grammar(rng).encode())
_spec = _budgeted(lambda rng: generate.spec(rng).encode())
SEEDS = generate.seeds()
_mutated = _budgeted(lambda rng: generate.mutate(rng, rng.choice(SEEDS)))
_declared = _budgeted(lambda rng: generate.with_declaration(rng, rng.choice(SEEDS)))
_spliced = _budgeted(lambda rng: generate.mutate(
    rng, generate.splice(rng, rng.choice(SEEDS), rng.choice(SEEDS))))


@pytest.mark.slow
@FUZZ
@given(st.integers(0, 2**64 - 1).map(random.Random))
def test_grammar_walks(workdir: str, rng: random.Random) -> None:
    _grammar(rng, workdir)


@pytest.mark.slow
@FUZZ
@given(st.integers(0, 2**64 - 1).map(random.Random))
def test_generated_machines(workdir: str, rng: random.Random) -> None:
    _spec(rng, workdir)


@pytest.mark.slow
@FUZZ
@given(st.integers(0, 2**64 - 1).map(random.Random))
def test_mutated_seeds(workdir: str, rng: random.Random) -> None:
    _mutated(rng, workdir)


@pytest.mark.slow
@FUZZ
@given(st.integers(0, 2**64 - 1).map(random.Random))
def test_seeds_with_a_declaration(workdir: str, rng: random.Random) -> None:
    _declared(rng, workdir)


@pytest.mark.slow
@FUZZ
@given(st.integers(0, 2**64 - 1).map(random.Random))
def test_spliced_seeds(workdir: str, rng: random.Random) -> None:
    _spliced(rng, workdir)


@pytest.mark.slow
def test_generators_reach_every_stage(workdir: str) -> None:
    """The generators are worth their time: files that fail to parse, files that fail a
    check, and files that check and compile, within the first 200 generated machines."""
    rng = random.Random(36)
    codes: set[tuple[str, int]] = set()
    syntax_errors = 0
    for _ in range(10):
        verdict = harness.judge(generate.from_grammar(rng).encode(), workdir, rng)
        codes |= set(verdict.codes.items())
        syntax_errors += verdict.syntax_error
        verdict = harness.judge(generate.mutate(rng, rng.choice(SEEDS)), workdir, rng)
        syntax_errors += verdict.syntax_error
    assert syntax_errors and ("check", 1) in codes
    path = os.path.join(workdir, "machine.afsm")
    for _ in range(200):
        text = generate.spec(rng)
        Path(path).write_text(text)
        if harness.run_main(["check", path])[0] == 0:
            codes |= set(harness.judge(text.encode(), workdir, rng).codes.items())
            break
    assert {("check", 0), ("prism", 0), ("jani", 0), ("dot", 0)} <= codes


@pytest.mark.slow
def test_through_a_real_process(tmp_path: Path) -> None:
    """The same properties through `python -m afsmc`, where the traceback would really be
    printed (no AFSMC_TRACEBACK) and the exit code is the process's. (Few processes:
    `check` and `fmt` take every file at once.)"""
    rng = random.Random(2026)
    machine = generate.spec(rng)
    while harness.judge(machine.encode(), str(tmp_path), rng).codes["check"] != 0:
        machine = generate.spec(rng)
    inputs = [machine.encode(), CORPUS[0].read_bytes(), generate.mutate(rng, SEEDS[0]),
              generate.from_grammar(rng).encode(), generate.with_declaration(rng, SEEDS[1])]
    paths = []
    for i, data in enumerate(inputs):
        paths.append(str(tmp_path / f"in{i}.afsm"))
        Path(paths[-1]).write_bytes(data)
    env = {k: v for k, v in os.environ.items() if k != "AFSMC_TRACEBACK"}
    for argv in (["check", *paths], ["fmt", "--diff", *paths],
                 ["compile", paths[0], "-t", "jani", "-o", "-"],
                 ["compile", paths[0], "-t", "prism", "-o", "-"]):
        proc = subprocess.run([sys.executable, "-m", "afsmc", *argv], capture_output=True,
                              text=True, env=env, timeout=300)
        assert proc.returncode in (0, 1), (argv, inputs, proc.stderr)
        assert "Traceback" not in proc.stderr and "internal error" not in proc.stderr, (
            argv, inputs, proc.stderr)
    assert proc.returncode == 0 and "module" in proc.stdout  # the machine compiled


def test_known_deep_constant_chain(workdir: str) -> None:
    """What the fuzzer found in the class of long expressions, which `generate.excluded`
    keeps out of the runs above: a mutation of the golden case of 5,050 nested minus signs
    that fell under the parser's limit of 5,000 took 10 s to check, as the resolver folded
    each constant level of the chain anew. Here 3,000 levels over a constant, generated
    (about 0.3 s of CPU now that each level is evaluated once)."""
    text = ("machine m;\nconst int K = 1;\nmode S initial;\n"
            f"action Go in S weight ({'- ' * 3000}K) {{ skip; }}\n")
    path = os.path.join(workdir, "deep.afsm")
    Path(path).write_text(text)
    code, _, failure = harness.run_main(["check", path], cpu_limit=3.0)
    assert failure is None, failure.kind
    assert code in (0, 1)
