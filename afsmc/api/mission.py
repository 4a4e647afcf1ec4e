"""`Mission`: one loaded and checked .afsm file, the object the Python API hangs off.

``afsmc.load(path_or_text)`` parses, resolves and checks a file (or a text) as `afsmc check`
does and raises :class:`afsmc.AfsmError` with the same diagnostics if anything is an error.
From a mission: ``check()`` (its warnings), ``compile(target)`` (PRISM, JANI or DOT text),
``with_consts(**values)`` (another instance), ``verify()``, ``sweep()``, ``simulate()`` and
``diagram()``. The commands `check` and `compile` load and compile through this module.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from afsmc.api.errors import AfsmError
from afsmc.compiler import Checked, lowered
from afsmc.compiler import load as load_checked
from afsmc.diagnostics import CompileError, Diagnostic
from afsmc.files import read_source
from afsmc.lower.lowering import Lowered, Resolution
from afsmc.lower.reduce import Reductions
from afsmc.model import ir
from afsmc.text import literal

if TYPE_CHECKING:
    from afsmc.api.conform import Conformance
    from afsmc.api.diagram import Diagram
    from afsmc.api.results import Results
    from afsmc.api.sim_check import SimCheck
    from afsmc.api.simulate import Estimates
    from afsmc.api.sweep import Sweep
    from afsmc.report.document import Report

Value = str | bool | int | float
TEXT_PATH = "<text>"  # the name diagnostics give a mission loaded from a string

# target -> "module:function"; the function maps a Lowered model to {suffix: text}.
TARGETS: dict[str, str] = {
    "prism": "afsmc.backends.prism:files",
    "jani": "afsmc.backends.jani:files",
    "dot": "afsmc.backends.dot:files",
    "python": "afsmc.controllers.python:files",
    "c": "afsmc.controllers.c:files",
}
# The targets that write a controller: made from the checked model before the reductions
# (the robot's variables), so compile hands them a lowering without any.
CONTROLLERS = frozenset({"python", "c"})


def available_targets() -> dict[str, Callable[[Lowered], dict[str, str]]]:
    """The compile targets whose backend imports (a backend not installed is not offered)."""
    out = {}
    for name, ref in TARGETS.items():
        module, func = ref.split(":")
        try:
            out[name] = getattr(importlib.import_module(module), func)
        except (ImportError, AttributeError):
            continue
    return out


def target_notes(name: str, low: Lowered) -> list[Diagnostic]:
    """A backend's warnings about what it wrote (its optional `notes(low)`): JANI's W401."""
    notes = getattr(importlib.import_module(TARGETS[name].split(":")[0]), "notes", None)
    return list(notes(low)) if notes else []


def texts_of(consts: Mapping[str, Value] | None) -> dict[str, str]:
    """Constants as `--const` takes them: `True` -> "true", 5 -> "5"; a str as written."""
    return {k: literal(v) for k, v in (consts or {}).items()}


@dataclass(frozen=True)
class Mission:
    """A checked .afsm file with its open constants' values. Made by :func:`afsmc.load`
    (or :meth:`open` / :meth:`from_text`); immutable: :meth:`with_consts` makes another.

    ``path``: the file, or ``"<text>"`` for a mission given as text; ``text``: its source;
    ``consts``: the values given to open constants (as `--const` writes them);
    ``model``: the checked IR (:class:`afsmc.model.ir.Model`)."""

    path: str
    text: str = field(repr=False)
    consts: Mapping[str, str]
    checked: Checked = field(repr=False, compare=False)

    @classmethod
    def open(cls, path: str, consts: Mapping[str, Value] | None = None, *,
             text: str | None = None) -> Mission:
        """Load and check the file at `path` (or `text` under that name). Raises AfsmError."""
        overrides = texts_of(consts)
        try:
            source = read_source(path) if text is None else text
            checked = load_checked(path, overrides, text=source)
        except CompileError as exc:
            raise AfsmError.of(exc) from None
        return cls(path, source, overrides, checked)

    @classmethod
    def from_text(cls, text: str, consts: Mapping[str, Value] | None = None, *,
                  path: str = TEXT_PATH) -> Mission:
        """Load and check a mission written in a string. Raises AfsmError."""
        return cls.open(path, consts, text=text)

    # -- what the file declares --------------------------------------------------------
    @property
    def model(self) -> ir.Model:
        return self.checked.model

    @property
    def name(self) -> str:
        """The machine's name (`machine NAME;`)."""
        return self.model.name

    @property
    def properties(self) -> list[str]:
        """The declared properties' names, in order."""
        return [p.name for p in self.model.properties]

    @property
    def constants(self) -> dict[str, object]:
        """The open constants (`param`) and the values this instance uses."""
        return {c.name: c.value for c in self.model.constants if c.is_param}

    @property
    def diagnostics(self) -> list[Diagnostic]:
        """The warnings and notes of loading (errors raise AfsmError instead)."""
        return list(self.checked.diagnostics)

    def check(self) -> list[Diagnostic]:
        """What `afsmc check` reports on this file and constants: its warnings and notes (a
        mission with errors does not load: :func:`afsmc.load` raises AfsmError)."""
        return self.diagnostics

    def with_consts(self, **values: Value) -> Mission:
        """The same file with these open constants set (the others keep their values):
        ``m.with_consts(CELLS=6)`` is ``afsmc verify --const CELLS=6``. Raises AfsmError."""
        return Mission.open(self.path, {**self.consts, **values}, text=self.text)

    # -- compiling ---------------------------------------------------------------------
    def lowered(self, resolve: Resolution = "nondet",
                reductions: Reductions | None = None) -> Lowered:
        """The guarded commands every backend reads (`compile --resolve`; all the exact
        reductions unless `reductions` says otherwise). Raises AfsmError."""
        try:
            return lowered(self.model, resolve, reductions)
        except CompileError as exc:
            raise AfsmError.of(exc) from None

    def files(self, target: str = "prism", *, resolve: Resolution = "nondet",
              reductions: Reductions | None = None) -> dict[str, str]:
        """What `afsmc compile -t TARGET` writes: {suffix: text} (PRISM: ``.prism`` and
        ``.props``; JANI: ``.json``; DOT: ``.gv``; a controller, docs/robot.md: ``.py``
        for "python", ``.h`` and ``.c`` for "c", made without the reductions). By default
        every exact reduction, the symmetry of alike agents included where the mission and
        all its properties treat them alike (the header says which)."""
        targets = available_targets()
        if target not in targets:
            raise ValueError(f"target must be one of {', '.join(map(repr, targets))}; "
                             f"got {target!r}")
        if target in CONTROLLERS:
            reductions = Reductions.none()
        elif reductions is None:  # as `afsmc compile`: the symmetry too where it is exact
            reductions = Reductions(symmetry="auto")
        return targets[target](self.lowered(resolve, reductions))

    def compile(self, target: str = "prism", *, resolve: Resolution = "nondet",
                reductions: Reductions | None = None) -> str:
        """The mission in `target`'s language ("prism", "jani", "dot", "python", "c"), as
        one text: the output of `afsmc compile -t TARGET -o -` (PRISM: the model, then a line
        ``// ==== NAME.props`` and the properties)."""
        return joined(self.path, self.files(target, resolve=resolve, reductions=reductions))

    # -- Storm, the simulator and the diagram ------------------------------------------
    def verify(self, properties: Sequence[str] | str | None = None, **options: Any) -> Results:
        """Check the properties with Storm, as `afsmc verify` does and with its defaults.

        `properties`: names of declared properties (default: all of them). `options` are
        those of :func:`afsmc.verify.run` (the CLI's options): ``formulas=[...]`` (ad-hoc
        properties), ``engine`` ("auto", "sparse", "hybrid", "dd"), ``via`` ("prism",
        "jani"), ``solver``, ``max_states``, ``uniform``, ``bisimulation``, ``split``,
        ``reductions``, ``progress`` (a function that receives progress lines),
        ``strategy=True`` and ``witness=K`` (`--strategy`, `--witness K`; ``witness_dir``
        "min" or "max"), and whatever
        later versions of `afsmc verify` add. Raises AfsmError (with ``.partial``, the
        queries answered, if some failed)."""
        from afsmc.api.results import verify

        return verify(self, properties, **options)

    def sweep(self, variable: str | Mapping[str, Sequence[int | float | bool] | str],
              values: Sequence[int | float | bool] | str = (), *,
              properties: Sequence[str] | str | None = None, **options: Any) -> Sweep:
        """Each property at each value of one open constant (`afsmc sweep --const
        T=0:900:25`), or of the properties' step bound with ``variable="bound"`` (`afsmc
        sweep --bound`). `values`: a list, or a range text ``"0:900:25"`` (stop included) or
        ``"1,2,5"``. A mapping ``{"CELLS": "2:4", "ROUNDS": [1, 2, 3]}`` for `variable`
        sweeps the grid of several constants (`afsmc sweep --const CELLS=2:4 --const
        ROUNDS=1:3`). `options`: those of :func:`afsmc.verify.reports.sweep` (``jobs``,
        ``engine``, ``formulas``, ``dask``, ...). Raises AfsmError."""
        from afsmc.api.sweep import sweep

        return sweep(self, variable, values, properties=properties, **options)

    def simulate(self, runs: int = 100_000, **options: Any) -> Estimates:
        """Monte Carlo estimates of every declared property with confidence intervals, as
        `afsmc simulate` gives them: options ``seed`` (0), ``resolve`` ("uniform"),
        ``confidence`` (0.999), ``max_steps`` (100000), ``jobs`` (1), ``batch_size``,
        ``dask``, ``traces``, ``at`` ("draw": each run draws its interval probabilities
        uniformly from their intervals; "mid", "min", "max": every run there),
        ``strategy`` ("min:NAME" or "max:NAME": follow Storm's scheduler of property
        NAME), ``progress``. ``to_json()`` is `afsmc simulate --json`. Raises AfsmError
        (E407 if the mission declares no properties and no ``traces`` are asked for)."""
        from afsmc.api.simulate import simulate

        return simulate(self, runs, **options)

    def sim_check(self, runs: int = 10_000, **options: Any) -> SimCheck:
        """Re-run the simulation behind every `from sim ...` constant and judge the value
        in the file against it, as `afsmc sim-check` does: options ``seed`` (0),
        ``timeout`` (seconds per simulator), ``update`` (rewrite the drifted constants in
        the file), ``confidence`` (the tests' level where a constant states none; 0.999),
        ``progress`` (a function that receives a line per constant), ``data_root`` (the
        folder `from data` files must lie under; default: the file's folder). A drift
        is in the result (``.ok`` is False, ``.errors`` has E502), not raised. Raises
        AfsmError (a simulator failed: E505)."""
        from afsmc.api.sim_check import sim_check

        return sim_check(self, runs, **options)

    def report(self, properties: Sequence[str] | str | None = None, *, recheck: int = 0,
               baseline: str | os.PathLike[str] | None = None, tolerance: float = 0.0,
               sensitivity: bool = True, worst_case: bool = True, causes: bool = True,
               progress: Callable[[str], None] | None = None, **options: Any) -> Report:
        """The assurance case of `afsmc report` (docs/report.md): it shows inline in
        Jupyter, ``.save("report.html")`` (or ``.md``) writes it. `recheck`: re-run every
        `from sim` simulation with that many runs (0: not re-checked); `baseline`: an
        earlier `afsmc verify --json` file to compare with, flagging moves beyond
        `tolerance`; `sensitivity=False`, `worst_case=False` and `causes=False` leave out
        "What matters most", "The worst case" and "How it fails"; `options`: those of
        :meth:`verify` (``engine``, ``formulas``, ...). Raises AfsmError."""
        from afsmc.api.results import VERIFY_DEFAULTS, names
        from afsmc.report import baseline as base
        from afsmc.report.case import build, command
        from afsmc.report.document import Report
        from afsmc.verify.core.options import VerifyOptions

        formulas = options.pop("formulas", ())
        try:
            opts = VerifyOptions(**{**VERIFY_DEFAULTS, **options})
            old = None if baseline is None else base.read(os.fspath(baseline), self.name)
            case = build(self.path, dict(self.consts), options=opts,
                         properties=names(properties), recheck=recheck, baseline=old,
                         baseline_name="" if baseline is None else os.fspath(baseline),
                         tolerance=tolerance, formulas=formulas, text=self.text,
                         sensitivity=sensitivity, worst_case=worst_case, causes=causes,
                         progress=progress,
                         command=command(self.path, self.consts, names(properties), formulas,
                                         opts.engine),
                         generated="Made from the Python API.")
        except CompileError as exc:
            raise AfsmError.of(exc) from None
        return Report(case)

    def conform(self, logs: Sequence[str], *, update: bool = False,
                confidence: float | None = None) -> Conformance:
        """Check logged runs (files in the format of docs/robot.md) against the mission, as
        `afsmc conform` does: each step the spec does not allow (``.violations``, E720) and
        each probability and interval constant the steps exercise, judged as sim-check
        judges a simulation (``.evidence``; ``.errors`` has E721 for a drift). ``update``
        rewrites the drifted constants in the file. Raises AfsmError for bad logs
        (E710-E713) and a composed mission (E701)."""
        from afsmc.api.conform import conform_file

        if update and not os.path.isfile(self.path):
            raise ValueError(f"update rewrites the mission's file; {self.path} is not a file")
        return conform_file(self.path, self.consts, list(logs), update=update,
                            confidence=confidence, text=None if update else self.text)

    def diagram(self, **options: Any) -> Diagram:
        """The mission diagram (`afsmc diagram`): it shows inline in Jupyter, and
        ``.save("m.svg")`` writes it. Options: ``reach=True`` (Storm's probability of
        reaching each mode), ``resolve`` and ``max_states`` with it. Raises AfsmError."""
        from afsmc.api.diagram import diagram

        return diagram(self, **options)


def joined(path: str, files: Mapping[str, str]) -> str:
    """Several output files as one text, each after the first headed `// ==== NAME`."""
    stem = os.path.splitext(os.path.basename(path))[0]
    out = []
    for i, (suffix, text) in enumerate(files.items()):
        if i:
            out.append(f"\n// ==== {stem}{suffix}\n")
        out.append(text)
    return "".join(out)


def load(path_or_text: str | os.PathLike[str], *,
         consts: Mapping[str, Value] | None = None) -> Mission:
    """Load, resolve and check a mission, as `afsmc check` does.

    `path_or_text`: a path to a .afsm file, or the text of one (a string that holds a
    newline or a `;` and names no file). `consts`: open constants' values, e.g.
    ``{"CELLS": 6}`` (as ``--const CELLS=6``).

    Raises :class:`afsmc.AfsmError` with the diagnostics `afsmc check` reports if the file
    cannot be read or has an error; warnings are in :meth:`Mission.check`.

    >>> m = afsmc.load("examples/patrol.afsm")            # doctest: +SKIP
    >>> m.verify().to_pandas()                            # doctest: +SKIP
    """
    if isinstance(path_or_text, os.PathLike):
        return Mission.open(os.fspath(path_or_text), consts)
    if is_text(path_or_text):
        return Mission.from_text(path_or_text, consts)
    return Mission.open(path_or_text, consts)


def is_text(s: str) -> bool:
    """A mission's text rather than a file name: it has a line break or a `;`, and no
    file of that name exists."""
    return ("\n" in s or ";" in s) and not os.path.isfile(s)
