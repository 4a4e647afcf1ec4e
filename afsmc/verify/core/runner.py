"""Running a check: the Storm processes that answer each lowered model's queries.

:class:`CheckRun` holds one call of :func:`afsmc.verify.check` (its models, their answers so
far, the errors of failed queries); :class:`afsmc.verify.core.model_loop.ModelLoop` checks
one lowered model (the MDP, its uniform DTMC, or the only DTMC), one unit of queries per
Storm process. A failed query
does not stop the others: its error is raised at the end with every answer, so that one
query does not cost an hour's others.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

from afsmc.backends.prism import property_variants
from afsmc.compiler import lowered
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.lower.lowering import Lowered
from afsmc.lower.reduce import Reductions
from afsmc.model import ir
from afsmc.model.semantics import bounded_globally
from afsmc.verify.core.options import VerifyOptions
from afsmc.verify.engines.failures import (
    refuse_symbolic,
    symbolic_globals,
    writes_shared,
)
from afsmc.verify.engines.guard import (
    Progress,
    default_max_states,
    upper_bound,
)
from afsmc.verify.engines.jobs import choose_engine
from afsmc.verify.engines.storm import (
    Engine,
)
from afsmc.verify.engines.strategy_storm import Extracted, WitnessRequest
from afsmc.verify.outcome.results import (
    Checks,
    ModelStats,
    Partial,
    PropertyResult,
    shown,
)
from afsmc.verify.outcome.strategy import attach
from afsmc.verify.plan.deep import refuse_deep
from afsmc.verify.plan.precision import complement, rational_text
from afsmc.verify.plan.queries import (
    TERMINATES,
    complements,
    dual,
    duals_of,
    kept_note,
    query_text,
    readable,
)

# Above this many state-steps (states x step bound), a check runs in a child process.
IN_PROCESS_WORK = 500_000_000


def so_far(seconds: float) -> str:
    """The time a long check has taken, for its progress lines."""
    if seconds < 120:
        return f"{seconds:.0f} s so far"
    return f"{seconds / 60:.0f} min so far"


@dataclass(frozen=True)
class Options:
    """How :func:`afsmc.verify.check` runs Storm: the verification's options as given, and
    what `check` resolves of them for this call."""

    given: VerifyOptions
    all_states: bool  # Storm builds every reachable state (Job.all_states)
    precision: str | None  # sound mode within this, as Storm's rational (Job.precision)
    witness: WitnessRequest | None  # a query's most probable paths, resolved

    @classmethod
    def of(cls, o: VerifyOptions, all_states: bool, precision: float | None,
           witness: WitnessRequest | None) -> Options:
        """A check's settings from the verification's options: the precision it runs at
        (a requirement's default, from `sound_mode`) as Storm's rational, and the witness
        request resolved against its properties."""
        return cls(o, all_states, None if precision is None else rational_text(precision),
                   witness)


class CheckRun:
    """One call of `check`: the properties as asked (bounded G as their duals), the
    lowered models, and per model its stats, answers and check times so far."""

    def __init__(self, model: ir.Model, props: list[ir.Property], preserve: list[ir.Property],
                 engine: Engine, uniform: bool, progress: Progress | None,
                 reductions: Reductions | None, options: Options) -> None:
        self.started = time.perf_counter()
        self.options = options
        self.original = list(props)
        pairs = duals_of(self.original)
        # a dual's query -> the bounded-G query it gives, and the wording of that
        self.duals = {q: gives for q, (gives, _) in pairs.items()}
        self.texts = {q: text for q, (_, text) in pairs.items()}
        # a bounded G's query -> its dual's, whose value it is 1 minus (min and max swapped)
        self.asked_as = {query: its for its, query in self.duals.items()}
        self.progress: Progress | None = None
        if progress is not None:
            say, texts = progress, self.texts
            self.progress = lambda text: say(readable(text, texts))
        self.props = [dual(p) if bounded_globally(p) else p for p in props]
        preserve = [dual(p) if bounded_globally(p) else p for p in preserve]
        self.bound = upper_bound(model)
        self.engine, self.reason = choose_engine(engine, self.bound)
        if self.engine == "auto" and options.given.via == "prism" and writes_shared(model):
            # "auto" would count the states with Storm's symbolic builder, which builds
            # such a mission's PRISM wrongly (afsmc.verify.engines.failures.writes_shared)
            self.engine, self.reason = "sparse", (
                "the agents write shared variables, which Storm's symbolic builder gets "
                "wrong in PRISM: the sparse engine, under the memory guard")
        refuse_symbolic(self.props, model, self.engine, options.given.via)
        # Only the hybrid engine needs them ("auto" may still pick it after counting states).
        self.comp = complements(model, self.props) if self.engine in ("hybrid", "auto") else {}
        self.model = dataclasses.replace(model, properties=tuple(self.props) + tuple(
            p for n, p in sorted(self.comp.items())) + tuple(preserve))
        self.lows: list[tuple[str, Lowered, str]] = []
        first = lowered(self.model, "nondet", reductions)
        if first.network is not None and first.network.global_locals \
                and options.given.via == "prism" and self.engine != "sparse":
            # the symmetry reduction's agents write each other's variables: as shared ones
            if self.engine == "auto":
                self.engine, self.reason = "sparse", (
                    "under the symmetry reduction the agents write each other's variables, "
                    "which Storm's symbolic builder gets wrong in PRISM: the sparse engine, "
                    "under the memory guard")
            else:
                raise symbolic_globals(self.engine, first.model.composition,
                                       "each other's variables (--symmetry)")
        self.lows.append(("nondet", first, "MDP" if first.kind == "mdp" else "DTMC"))
        if self.model.is_nondeterministic and uniform:
            # (a composed mission's interleaving stays an MDP: no uniform model then)
            low = lowered(self.model, "uniform", reductions)
            if low.kind == "dtmc":
                self.lows.append(("uniform", low, "uniform DTMC"))
        for _, low, _ in self.lows:  # a counter too deep for an unwatched symbolic build
            refuse_deep(low, self.engine, options.given.max_states, default_max_states())
        self.stats: list[ModelStats | None] = []  # None: every process of that model failed
        self.values: list[dict[str, float]] = []
        self.timings: list[dict[str, float]] = []  # each query's check time, as `values`
        self.model_queries: list[list[str]] = []  # each model's queries, as `values`
        # Failures of one query (not of the model): the other queries go on, and these are
        # raised at the end with every answer.
        self.errors: list[Diagnostic] = []
        # --exact: each model's (by resolution) values as `num/den`, by query
        self.exact: dict[str, dict[str, str]] = {}
        self.extracted: list[Extracted] = []  # schedulers and paths (Options.strategy)
        # a later model's answers given by an earlier one's process, by resolution: the
        # uniform DTMC's from the MDP's exploration (explicit.Uniform), with its stats
        self.beside: dict[str, tuple[dict[str, float], dict[str, float], ModelStats]] = {}

    def kept(self, what: str, vals: dict[str, float]) -> list[Diagnostic]:
        """The note of what the finished models and this one have answered."""
        done = [*zip([w for _, _, w in self.lows], self.values, strict=False), (what, vals)]
        return kept_note(done, self.comp, self.duals)

    def results(self) -> list[PropertyResult]:
        """One result per property from the models answered so far (None where not),
        each built whole: the schedulers and paths in it too."""
        first = self.lows[0][1]
        out = []
        for p in self.original:
            values: dict[str, float] = {}
            exacts: dict[str, str] = {}
            seconds: dict[str, float] = {}
            variants = ([(opt, 0, name) for name, opt in property_variants(first, p)]
                        + ([("uniform", 1, p.name)] if len(self.lows) > 1 else [])
                        if first.kind == "mdp" else [("value", 0, p.name)])
            for key, which, name in variants:
                if which >= len(self.values):
                    continue
                query = self.asked_as.get(name, name)
                v = self.values[which].get(query)
                if v is None:
                    continue
                values[key] = 1.0 - v if name in self.asked_as else v
                exact = self.exact.get(self.lows[which][0], {}).get(query)
                if exact is not None:
                    exacts[key] = complement(exact) if name in self.asked_as else exact
                secs = self.timings[which].get(query)
                if secs is not None:
                    seconds[key] = secs
            out.append(PropertyResult(
                p.name, shown(p), p.kind, min=values.get("min"), max=values.get("max"),
                uniform=values.get("uniform"), value=values.get("value"), seconds=seconds,
                threshold=p.threshold, exact=exacts))
        if self.extracted:
            out = attach(out, self.original, first, self.extracted, self.asked_as)
        return out

    def partial(self, more: dict[str, float] | None = None,
                secs: dict[str, float] | None = None,
                built: ModelStats | None = None) -> Partial | None:
        """What to keep of a failed run (None if nothing was answered). `more`, `secs` and
        `built`: the values, times and stats of the model being checked, if it stops before
        the end of its loop (its Pmax still as complements: converted as `kept_note` does)."""
        n = len(self.values)
        if more is not None:
            more = dict(more)
            if more.get(TERMINATES) == 1.0:
                more |= {name: 1.0 - more[rest.name] for name, rest in self.comp.items()
                         if name != TERMINATES and rest.name in more}
            self.values.append(more)
            self.timings.append(secs or {})
        try:
            rs = self.results()
        finally:
            del self.values[n:], self.timings[n:]
        if not any(getattr(r, k) is not None for r in rs
                   for k in ("min", "max", "uniform", "value")):
            return None
        models = [*self.stats, built, None, None]
        return Partial(models[0], models[1], rs)

    def finish(self) -> Checks:
        """The checks' results, or a CompileError with every error and what was answered;
        every query without a value is named, whatever the reason it was not asked."""
        missing = [f"{query_text(n, self.duals)} on the {what}"
                   for (_, _, what), names, vals in zip(self.lows, self.model_queries,
                                                        self.values, strict=True)
                   for n in names if n not in vals]
        errors = self.errors
        if missing and not errors:  # a bug: say so rather than fail below
            errors.append(Diagnostic(codes.E406, Severity.ERROR, "internal error: no answer and no "
                                     f"error for {', '.join(missing)}", None))
        if errors:
            notes = kept_note(list(zip([w for _, _, w in self.lows], self.values, strict=True)),
                              self.comp, self.duals, "the other queries were answered")
            if missing:
                text = "not answered: " + ", ".join(missing)
                notes = ([dataclasses.replace(notes[0], message=f"{notes[0].message}\n{text}")]
                         if notes else [Diagnostic(codes.N412, Severity.NOTE, text, None)])
            raise CompileError([*errors, *notes], self.partial())
        main, *uniform_model = self.stats  # the MDP or only DTMC, then the uniform DTMC if any
        assert main is not None and None not in uniform_model  # else `errors` above
        return Checks(main, uniform_model[0] if uniform_model else None, self.results(),
                      symmetry=self.lows[0][1].symmetry)
