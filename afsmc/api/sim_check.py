"""`SimCheck`: what :meth:`Mission.sim_check` returns, the simulation behind every
`from sim ...` constant re-run and judged against the value in the file (`afsmc
sim-check`); ``to_pandas()``, ``to_json()`` and ``_repr_html_``.

`afsmc sim-check FILE` runs through :func:`sim_check_file` here, as the method does.
"""

from __future__ import annotations

import dataclasses
import datetime
import html
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from afsmc.api.errors import AfsmError
from afsmc.check.sim_sources import data_kind
from afsmc.compiler import Checked, load
from afsmc.diagnostics import CompileError, Diagnostic, Severity, codes
from afsmc.files import write_atomic
from afsmc.model import ir
from afsmc.sim.evidence import Evidence, judge, rewrite
from afsmc.simlib import datafile, sandbox

if TYPE_CHECKING:
    import pandas as pd

    from afsmc.api.mission import Mission

Say = Callable[[str], None]
COLUMNS = ("constant", "simulation", "declared", "mean", "mean_low", "mean_high", "cdf_lo",
           "cdf_hi", "hull", "verdict", "suggestion")


def sim_check(mission: Mission, runs: int = 10_000, *, seed: int = 0,
              timeout: float = sandbox.DEFAULT_TIMEOUT, update: bool = False,
              confidence: float | None = None, progress: Say | None = None,
              data_root: str | None = None) -> SimCheck:
    """:meth:`Mission.sim_check`: :func:`sim_check_file` on the mission's file (re-read
    as it is on disk for `update`, which rewrites it) or text, and constants."""
    if update and not os.path.isfile(mission.path):
        raise ValueError(f"update rewrites the mission's file; {mission.path} is not a file")
    return sim_check_file(mission.path, mission.consts, None if update else mission.text,
                          runs=runs, seed=seed, timeout=timeout, update=update,
                          confidence=confidence, progress=progress, data_root=data_root)


def sim_check_file(path: str, consts: Mapping[str, str], text: str | None = None, *,
                   runs: int = 10_000, seed: int = 0,
                   timeout: float = sandbox.DEFAULT_TIMEOUT, update: bool = False,
                   budget: int | None = None, confidence: float | None = None,
                   progress: Say | None = None, data_root: str | None = None) -> SimCheck:
    """The one way afsmc judges simulated constants, for `afsmc sim-check` and
    :meth:`Mission.sim_check`. Each simulator runs `runs` times in its own process
    (stopped after `timeout` seconds or past `budget` bytes; default: the sandbox's share
    of the free memory). `update` rewrites the drifted constants in the file, with a
    provenance comment, if the new text checks. `confidence`: the level of the statistical
    tests of constants whose declaration states none (default 0.999). A constant backed by
    a data file (`from data ...`) is judged on the file's rows instead of runs; the file
    must lie under `data_root` (default: the spec's folder; see afsmc.simlib.datafile).
    `progress` receives a line per constant.

    A drift is a result, not an exception: ``SimCheck.errors`` holds E502 (E508 if no
    value fits the constant's rule). Raises AfsmError: the file's errors, E505 (a
    simulator failed), E509 (the update would not check), E003 (the file cannot be
    written); ValueError for fewer than 2 runs."""
    if runs < 2:
        raise ValueError(f"runs must be at least 2; got {runs!r}")
    say = progress or (lambda line: None)
    if budget is None:
        budget = sandbox.memory_budget()
    if text is None:
        try:
            with open(path, encoding="utf-8", newline="") as f:
                text = f.read()  # newline="": an update must keep every other byte
        except (OSError, UnicodeDecodeError):
            text = None  # loading reports it (E001)
    checked = load_sourced(path, consts, text, say)
    sourced = [c for c in checked.model.constants if c.source is not None]
    results = judge_all(path, sourced, runs, seed, timeout, budget, say, confidence, data_root)
    by_name = {c.name: c for c in sourced}
    drifted = [e for e in results if not e.consistent]
    # No value its own rule accepts (an int whose accepted range holds no integer):
    # an update would write a value the next sim-check rejects again.
    unfit = [Diagnostic(
        codes.E508, Severity.ERROR,
        f"constant '{e.name}' has drifted from {_origin(e)} (mean {e.mean:.4g}), and "
        f"no {by_name[e.name].type.value} fits the rule: it accepts {e.accept}",
        by_name[e.name].span, hint="widen its `tolerance`, or declare the constant double")
        for e in drifted if not e.fits]
    drifted = [e for e in drifted if e.fits]
    updated: list[Evidence] = []
    if update and drifted:
        assert text is not None
        update_constants(path, consts, text, drifted, by_name)
        updated = drifted
    # Nothing to reject at this many runs: said, rather than called consistent.
    few = [Diagnostic(
        codes.W503, Severity.WARNING, f"constant '{e.name}': {e.runs} runs of '{e.ref}' are too "
        f"few to judge it (the rule accepts {e.accept})", by_name[e.name].span,
        hint="raise --runs: the quantiles of the rule need more samples to be bounded")
        for e in results if e.inconclusive]
    errors = unfit + ([] if updated else [Diagnostic(
        codes.E502, Severity.ERROR,
        f"constant '{e.name}' = {e.declared} has drifted from {_origin(e)} "
        f"(mean {e.mean:.4g}; the rule accepts {e.accept})", by_name[e.name].span,
        hint=f"the simulation suggests {e.suggestion}; `afsmc sim-check --update` rewrites it")
        for e in drifted])
    return SimCheck(path, runs, seed, results, errors, few, updated)


def load_sourced(path: str, consts: Mapping[str, str], text: str | None, say: Say) -> Checked:
    """The checked model. When the only errors are params without a value (E206), the
    model without its checks, if no simulated constant reads those params (said)."""
    try:
        return load(path, dict(consts), text=text)
    except CompileError as exc:
        errors = [d for d in exc.diagnostics if d.is_error]
        if not errors or any(d.code != codes.E206 for d in errors):
            raise AfsmError.of(exc) from None
        # Only params without a value: the simulated constants may not need them.
        try:
            checked = load(path, dict(consts), text=text, run_checks=False, open_params=True)
        except CompileError:
            raise AfsmError.of(exc) from None
    missing, reads = checked.open_params, checked.open_reads
    needed = sorted({p for c in checked.model.constants if c.source is not None
                     for p in reads.get(c.name, ())})
    if needed:
        raise AfsmError([missing[p] for p in needed])
    open_ = sorted(missing)
    has, it = ("has", "it") if len(open_) == 1 else ("have", "them")
    say(f"sim-check: {', '.join(open_)} {has} no value, and no simulated constant "
        f"depends on {it}: the simulated constants are judged without the model's other "
        "checks (`afsmc check --const ...` runs those)")
    return checked


def _origin(e: Evidence) -> str:
    """Where a constant's evidence comes from, for a message."""
    return f"simulation '{e.ref}'" if e.seed is not None else e.ref


def judge_all(path: str, sourced: list[ir.Constant], runs: int, seed: int, timeout: float,
              budget: int | None, say: Say, confidence: float | None = None,
              data_root: str | None = None) -> list[Evidence]:
    """Each simulated constant judged against its simulation, run in a child process
    (afsmc.simlib.sandbox), a progress line before each; AfsmError E505 if a simulator
    fails in any way: an exception, an exit, a hang past `timeout`, too much memory."""
    results: list[Evidence] = []
    started = time.monotonic()
    for i, c in enumerate(sourced, 1):
        assert c.source is not None
        if c.source.column is not None:  # a data file: its rows are the runs
            say(f"sim-check: [{i}/{len(sourced)}] {c.name} <- {c.source.display} "
                f"({time.monotonic() - started:.1f} s)")
            try:
                results.append(_from_data(path, c, confidence, data_root))
            except CompileError as exc:
                raise AfsmError.of(exc) from None
            continue
        say(f"sim-check: [{i}/{len(sourced)}] {c.name} <- {c.source.ref} "
            f"({runs} runs, {time.monotonic() - started:.1f} s)")
        try:
            x = sandbox.sample(c.source.ref, runs, seed, timeout=timeout, budget=budget)
            bad = int(x.size - np.count_nonzero(np.isfinite(x)))
            if bad:
                raise sandbox.SimulatorFailure(f"{bad:,} of its {x.size:,} samples are not "
                                               "finite numbers (inf or nan)")
            with np.errstate(all="ignore"):  # a sum past 1e308 is inf, and said so
                results.append(judge(c, runs, seed, samples=x, confidence=confidence))
        except Exception as exc:  # a broken third-party simulator: report, don't crash
            raise AfsmError([Diagnostic(
                codes.E505, Severity.ERROR, f"simulator '{c.source.ref}' failed: {exc}",
                c.source.span)]) from None
    return results


def _from_data(path: str, c: ir.Constant, confidence: float | None,
               data_root: str | None) -> Evidence:
    """A constant backed by a data file judged by the rule of its shape, the file's values
    standing for the runs (a `prob`'s column holds outcomes)."""
    assert c.source is not None
    x = datafile.read(path, c, outcomes=c.declared_type == "prob", data_root=data_root)
    e = judge(c, len(x), 0, samples=x, confidence=confidence, kind=data_kind(c))
    return dataclasses.replace(e, ref=c.source.display, seed=None)


def update_constants(path: str, consts: Mapping[str, str], text: str, drifted: list[Evidence],
            by_name: dict[str, ir.Constant]) -> None:
    """Rewrite the drifted constants in the file, if the new text checks as `afsmc check`
    would check it; AfsmError (the file unchanged) if it cannot."""
    date = _today()
    changes = {e.name: (e.suggestion, f"{e.ref}, {e.runs} runs, seed {e.seed}, {date}"
                        if e.seed is not None else f"{e.ref}, {e.runs} rows, {date}")
               for e in drifted}
    new = rewrite(text, path, changes)
    refused = _refuse(path, consts, text, new, drifted, by_name)
    if refused is not None:
        raise AfsmError(refused)
    # Rewriting the input is the point here: no `protect`; keep its line endings and mode.
    try:
        write_atomic(path, new, newline=None)
    except CompileError as exc:  # E003: the file cannot be written (it is left as it was)
        raise AfsmError.of(exc) from None


def _refuse(path: str, consts: Mapping[str, str], old: str, new: str, drifted: list[Evidence],
            by_name: dict[str, ir.Constant]) -> list[Diagnostic] | None:
    """E509 at each drifted constant if the rewritten file has an error the file as it is
    does not have (checked as `afsmc check` checks it), else None."""
    def errors(text: str) -> list[Diagnostic]:
        try:
            load(path, dict(consts), text=text)
        except CompileError as exc:
            return [d for d in exc.diagnostics if d.is_error]
        return []
    after = errors(new)
    if not after:
        return None
    before = {(d.code, d.message) for d in errors(old)}
    fresh = [d for d in after if (d.code, d.message) not in before]
    if not fresh:
        return None  # the file had these errors already (params without a value: E206)
    first = fresh[0]
    return [Diagnostic(
        codes.E509, Severity.ERROR,
        f"--update would write {e.name} = {short_text(e.suggestion)}, which does not check: "
        f"{first.code} {short_text(first.message, 100)}; {path} is left unchanged",
        by_name[e.name].span,
        hint=f"the simulation's mean is {e.mean:.4g}: check simulator '{e.ref}', or set the "
             "value by hand") for e in drifted]


def short_text(value: str, most: int = 40) -> str:
    return value if len(value) <= most else f"{value[:most]}... ({len(value):,} characters)"


def _today() -> str:
    # SOURCE_DATE_EPOCH (reproducible builds) pins the date in the provenance comment.
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    when = (datetime.datetime.fromtimestamp(int(epoch), datetime.UTC) if epoch and epoch.isdigit()
            else datetime.datetime.now(datetime.UTC))
    return when.date().isoformat()


@dataclass(frozen=True)
class SimCheck:
    """The judged constants (``evidence``, one :class:`afsmc.sim.evidence.Evidence` each),
    the ``errors`` (E502 drifted, E508 no value fits the rule), the ``warnings`` (W503 too
    few runs to judge) and the constants an update rewrote (``updated``)."""

    path: str
    runs: int
    seed: int
    evidence: list[Evidence]
    errors: list[Diagnostic] = field(default_factory=list)
    warnings: list[Diagnostic] = field(default_factory=list)
    updated: list[Evidence] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """No constant drifted (or each drifted one was updated): `sim-check`'s exit 0."""
        return not self.errors

    @property
    def diagnostics(self) -> list[Diagnostic]:
        return self.errors + self.warnings

    def __getitem__(self, name: str) -> Evidence:
        for e in self.evidence:
            if e.name == name:
                return e
        raise KeyError(f"no simulated constant {name!r}")

    def to_json(self) -> dict[str, object]:
        """The object `afsmc sim-check --json` prints."""
        return {"file": self.path, "runs": self.runs, "seed": self.seed,
                "updated": [e.name for e in self.updated],
                "constants": [e.to_json() for e in self.evidence],
                "diagnostics": [d.to_json() for d in self.diagnostics]}

    def rows(self) -> list[dict[str, object]]:
        return [{"constant": e.name, "simulation": e.ref, "declared": e.declared,
                 "mean": e.mean, "mean_low": e.mean_low, "mean_high": e.mean_high,
                 "cdf_lo": e.cdf_lo, "cdf_hi": e.cdf_hi,
                 "hull": f"[{e.hull[0]}, {e.hull[1]}]" if e.hull else None,
                 "verdict": e.verdict, "suggestion": e.suggestion if e.fits else None}
                for e in self.evidence]

    def to_pandas(self) -> pd.DataFrame:
        """One row per simulated constant, indexed by its name: ``simulation``,
        ``declared`` (as written), ``mean`` with its confidence interval ``mean_low`` and
        ``mean_high``, ``cdf_lo`` and ``cdf_hi`` (the samples' CDF at an interval's ends),
        ``hull``, ``verdict`` ("consistent", "drifted", "inconclusive") and ``suggestion``
        (the value an update writes)."""
        import pandas as pd

        df = pd.DataFrame(self.rows(), columns=list(COLUMNS)).set_index("constant")
        for k in ("cdf_lo", "cdf_hi"):
            df[k] = df[k].astype(float)
        return df

    def _repr_html_(self) -> str:
        caption = (f"{html.escape(self.path)}: {len(self.evidence)} constant(s), "
                   f"{sum(not e.consistent for e in self.evidence)} drifted; {self.runs:,} "
                   f"runs, seed {self.seed}")
        table: str = self.to_pandas().to_html(na_rep="-", float_format=lambda v: f"{v:.4g}")
        return f"<div><p>{caption}</p>{table}</div>"
