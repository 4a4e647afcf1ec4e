"""Verification with Storm (through stormpy): the library behind `afsmc verify` and `afsmc sweep`.

For people, the Python API is :func:`afsmc.load` (afsmc.api): ``Mission.verify`` and
``Mission.sweep`` call ``run`` and ``sweep`` below with the command line's defaults, and give
tables and plots. Other tools (benchmarks, Monte Carlo cross-checks) call these functions
directly, with their own defaults (``engine="sparse"``, where the commands use "auto"). Every
function raises :class:`afsmc.diagnostics.CompileError` carrying diagnostics (codes E4xx for
Storm's side) instead of letting a Storm exception escape. When some queries fail and others
were answered, the error's ``partial`` keeps the answers: a :class:`Partial` (``.model``,
``.uniform_model``, ``.properties``, None where a query has no value) from ``run`` and
``check``, a ``SweepResult`` of the points evaluated (whole or in part) from ``sweep``.

``VerifyOptions(via="prism", engine="sparse", solver="auto", max_states=None,
memory_budget=None, uniform=True, isolate=None, reductions=None, bisimulation=False,
split=False, precision=None, exact=False, strategy=False, witness=None, witness_dir=None,
witness_target=None)``
    Every option of a verification, frozen (afsmc.verify.core.options). ``run``, ``check``
    and ``sweep`` take one as ``options=``, or its fields as keyword arguments.

``run(path, options=None, *, consts=None, properties=(), formulas=(), progress=None,
text=None, **option_fields) -> VerifyResult``
    Load, check and lower the file, build it with Storm and check the properties: the ones
    named in `properties` (default: every declared one, unless there are ad-hoc formulas:
    then none) plus each ad-hoc formula in
    `formulas` (afsm property syntax, e.g. ``'P=? [ F "done" ]'``, named ``adhoc``,
    ``adhoc2``...). `consts` gives open constants (``{"CELLS": "5"}``). For a machine with
    interval constants the floor/ceil MDP gives ``min``/``max`` and, unless
    ``uniform=False``, the uniform DTMC gives ``uniform``; otherwise ``value`` is set.
    `max_states` (default: derived from free memory) stops larger models with E405;
    `isolate` forces (True) or forbids (False) the watched child process (default: only
    when the upper bound exceeds 200,000 states). `progress(text)` receives progress lines.
    The values are bounds over everything the mission leaves uncertain
    (docs/verification.md, "What a result means"): with interval probabilities ``min`` and
    ``max`` come from Storm's parametric engine and the midpoint's answer is each
    property's ``reference``.
    ``strategy=True``: each MDP property's ``.strategy`` is ``{"min": [...], "max": [...]}``
    of :class:`afsmc.verify.outcome.strategy.StrategyEntry` (constant, end, value, action, mode,
    states, when); ``witness=(name, K)`` (name None: the only property) with
    ``witness_dir="min"|"max"`` (default max) sets that property's ``.witnesses``, the K
    most probable paths into its target (:class:`afsmc.verify.outcome.witness.Witness`: probability,
    steps of mode, action, probability, changes). Both from Storm's sparse engine; E415 for
    a request without an answer (docs/verification.md, "Strategies and failure paths").

    ``precision=EPS`` checks with Storm's sound value iteration (every value within EPS of
    the true one); ``exact=True`` builds over rationals and solves exactly (sparse engine).
    A property with a threshold (a requirement, ``P>=0.65 [ ... ]``) makes the check sound
    at ``precision.DEFAULT_PRECISION`` (1e-6) unless one of them is given, and gets a
    ``verdict`` (:mod:`afsmc.verify.outcome.verdicts`: holds, fails, depends, undecided).

``VerifyResult``: ``.model`` / ``.uniform_model`` (:class:`ModelStats`: type, states,
transitions, choices, parse/build/check times), ``.properties`` (list of
:class:`PropertyResult`: name, formula, kind, min, max, uniform, value; for requirements
``threshold`` and ``verdict``; ``error``, the bound on every value's error, 0 exact, None
unguaranteed; ``exact``, the values as fractions under ``exact=True``), ``.property(name)``,
``.kind``, ``.upper_bound``, ``.to_json()`` (the ``afsmc verify --json`` object).

``check(model, props, options=None, *, progress=None, preserve=(), all_states=False,
witness=None, **option_fields) -> Checks``
    The same on an already loaded :class:`afsmc.model.ir.Model` and a list of
    :class:`afsmc.model.ir.Property` (uniquely named), for callers that build properties.

``sweep(path, variable, values, *, kind="const", consts=None, properties=(), formulas=(),
jobs=None, dask=None, progress=None, text=None, options=None, **option_fields)
-> SweepResult``
    Evaluate the properties for each value of one open constant (``kind="const"``) or of
    the step bound of the properties (``kind="bound"``: ``F<=k``, ``C<=k``, ``I=k``; a property
    without a step bound is E410, raised before any point; the model is built once per chunk
    of bounds). Points run in `jobs` local processes (default: the
    number of cores; 1 runs in this process) or, with ``dask="tcp://host:8786"``, on that
    Dask cluster (a ``distributed.Client`` or an address). ``SweepResult.points`` is a list
    of :class:`SweepPoint` (x, properties, states, transitions) in the order of `values`;
    ``to_csv()``, ``to_json()``, ``plot(path)`` write the outputs, ``figure()`` is the
    plot as a matplotlib Figure; ``curve(name, key)`` gives one curve.

``parse_values(text) -> list[int | float]``: ``"0:900:25"`` (inclusive) or ``"1,2,5"``.
``upper_bound(model) -> int``: modes × the product of the variables' ranges.

The subpackages, each importing only those before it (docs/architecture.md): ``plan``
(what to ask: the queries of each property, precision and exact modes), ``engines`` (build
and solve: Storm's processes, afsmc's explorer, the parametric engine), ``outcome`` (one
typed answer per property: results, verdicts, strategies, witnesses), ``core`` (``run``,
``check``, ``VerifyOptions``, the bounds over everything uncertain), ``reports`` (sweeps,
regions, JUnit).
"""

from afsmc.verify.core.api import Loaded, check, load_with_formulas, run, select
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.engines.guard import default_max_states, upper_bound
from afsmc.verify.outcome.results import Checks, ModelStats, Partial, PropertyResult, VerifyResult
from afsmc.verify.reports.sweep import sweep
from afsmc.verify.reports.sweep_result import SweepPoint, SweepResult
from afsmc.verify.reports.sweep_values import parse_values

__all__ = [
    "Checks",
    "Loaded",
    "ModelStats",
    "Partial",
    "PropertyResult",
    "SweepPoint",
    "SweepResult",
    "VerifyOptions",
    "VerifyResult",
    "check",
    "default_max_states",
    "load_with_formulas",
    "parse_values",
    "run",
    "select",
    "sweep",
    "upper_bound",
]
