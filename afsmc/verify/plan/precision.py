"""How sure a value is: Storm's sound and exact modes, and the error bound they guarantee.

By default Storm stops value iteration when the values change little, which bounds nothing:
on patrol its `finish` min was 3.7e-8 off the exact value. A requirement's verdict needs a
guarantee, so a check with a requirement (or `--precision EPS`) runs in sound mode: Storm's
sound value iteration, which iterates from below and from above and stops when the two are
within EPS, so that every value is within EPS of the true one (absolute). `--exact` builds
the model over rationals and solves it exactly (sparse engine only): the error is 0.

These functions run inside the Storm process (afsmc.verify.engines.storm) and on its data.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Any

# The guarantee of a requirement's values when the user names none (--precision).
DEFAULT_PRECISION = 1e-6
# Over interval probabilities (afsmc.verify.engines.parametric): how close to the true extreme
# Storm's parameter lifting refines a property's bound (absolute). A different quantity
# from the above: a refinement over regions of the box, not a solver's stopping rule; the
# lifted models themselves are solved by sound value iteration to a relative
# PARAMETER_SOLVER_ERROR, which adds to it.
PARAMETER_PRECISION = 1e-4
PARAMETER_SOLVER_ERROR = 1e-6
# The engines that have a sound method: the dd engine iterates on decision diagrams and
# ignores Storm's soundness setting (measured: the same values with and without it).
SOUND_ENGINES = ("auto", "sparse", "hybrid")
# --exact builds the model over rationals: Storm's sparse engine only.
EXACT_ENGINES = ("auto", "sparse")


def rational_text(eps: float) -> str:
    """`1e-06` -> `1/1000000`: the decimal the user wrote, as Storm's rational."""
    f = Fraction(repr(eps))
    return f"{f.numerator}/{f.denominator}"


def check_options(precision: float | None, exact: bool, engine: str) -> str | None:
    """Why `precision`/`exact` cannot be used with `engine` (a message), or None."""
    if precision is not None and not (precision > 0 and precision < 1):
        return f"the precision must lie strictly between 0 and 1, not {precision!r}"
    if exact and precision is not None:
        return "--exact and --precision exclude each other: exact values have no error"
    if exact and engine not in EXACT_ENGINES:
        return (f"--exact needs the sparse engine (Storm builds exact models as sparse "
                f"matrices only), not {engine}")
    if precision is not None and engine not in SOUND_ENGINES:
        return (f"the {engine} engine has no sound method (it ignores Storm's soundness "
                "setting), so its values carry no error bound: use --engine sparse, hybrid "
                "or auto")
    return None


def iterative_environment(stormpy: Any, dd_memory_mb: int, min_max: str, native: str,
                          precision: str, relative: bool) -> Any:
    """Storm's environment for iterative checks: an MDP's min/max by Storm's MinMaxMethod
    `min_max`, a DTMC's linear equations by its own (native) solver's method `native`,
    both stopping at `precision` (a rational text), relative or absolute."""
    from stormpy import developer

    env = stormpy.Environment()
    env.dd().sylvan().maximal_memory = dd_memory_mb  # as built (Sylvan is set up once)
    mm = env.solver().min_max()
    mm.method = getattr(developer.MinMaxMethod, min_max)
    mm.precision = stormpy.Rational(precision)
    mm.relative_termination_criterion = relative
    env.solver().set_linear_equation_solver_type(developer.EquationSolverType.NATIVE)
    nat = env.solver().native()
    nat.method = getattr(developer.NativeLinearEquationSolverMethod, native)
    nat.precision = stormpy.Rational(precision)
    nat.relative_termination_criterion = relative
    return env


def sound_environment(stormpy: Any, precision: str, dd_memory_mb: int) -> Any:
    """Storm's environment for sound checks within `precision` (a rational text), absolute:
    sound value iteration for an MDP's min/max and a DTMC's linear equations."""
    env = iterative_environment(stormpy, dd_memory_mb, "SOUND_VALUE_ITERATION",
                                "SOUND_VALUE_ITERATION", precision, relative=False)
    env.solver().force_soundness = True
    return env


def exact_environment(stormpy: Any) -> Any:
    """Storm's environment for exact solutions of an exact (rational) model."""
    env = stormpy.Environment()
    env.solver().force_exact = True
    return env


def build_exact(stormpy: Any, program: Any, props: list[Any], extract: Any = None) -> Any:
    """The sparse model over rationals: every probability exactly as written (0.1 is 1/10);
    with the state valuations and choice labels that `extract` (a strategy_storm.Extract,
    or None) reads."""
    if extract is None:
        return stormpy.build_model[stormpy.Rational](program, props)
    from afsmc.verify.engines.strategy_storm import builder_options

    return stormpy.build_model[stormpy.Rational](
        program, options=builder_options(stormpy, props, program, extract))


def exact_text(value: Any) -> str | None:
    """A Storm rational as `num/den` (or an integer); None for anything else."""
    text = str(value).strip()
    try:
        Fraction(text)
    except (ValueError, ZeroDivisionError):
        return None
    return text


def complement(text: str) -> str:
    """1 - an exact value (a bounded G from its dual), as `num/den`."""
    f = 1 - Fraction(text)
    return f"{f.numerator}/{f.denominator}"


def nearest(text: str) -> float:
    """The double nearest an exact value (Storm's own conversion can be one ulp off)."""
    return float(Fraction(text))
