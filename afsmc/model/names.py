"""Names the generated PRISM/JANI/Storm inputs cannot use, and helpers for naming."""

from __future__ import annotations

import difflib
from collections.abc import Iterable

# PRISM's keywords (prism/PrismParser.jj) and the operators of Storm's property grammar.
PRISM_KEYWORDS = frozenset(["A", "bool", "clock", "const", "ctmc", "C", "double", "dtmc", "E", "endinit", "endinvariant", "endmodule", "endobservables", "endrewards", "endsystem", "false", "formula", "filter", "func", "F", "global", "G", "init", "invariant", "I", "int", "label", "max", "mdp", "min", "module", "X", "nondeterministic", "observable", "observables", "of", "Pmax", "Pmin", "P", "pomdp", "popta", "probabilistic", "prob", "pta", "rate", "rewards", "Rmax", "Rmin", "R", "S", "stochastic", "system", "true", "U", "W"])
STORM_PROPERTY_WORDS = frozenset(["T", "X", "Y", "S", "F", "G", "U", "W", "R", "P", "I", "C", "E", "A", "multi", "quantile", "LRA", "MP", "HOA"])
# Storm's PRISM parser refuses its other keywords (storm/parser/PrismParser.h) as any name,
# even the quoted names of labels and reward structures; stormpy 2.0 refuses all but
# player/endplayer, which newer Storm releases reserve too.
STORM_KEYWORDS = frozenset(["ctmdp", "ma", "smg", "floor", "ceil", "atLeastOneOf", "atMostOneOf", "exactlyOneOf", "player", "endplayer"])
# afsmc's own keywords (grammar/afsm.lark) can never be names, but are listed for hints.
AFSM_KEYWORDS = frozenset(["machine", "const", "param", "var", "mode", "action", "hazard", "formula", "label", "rewards", "property", "in", "when", "weight", "goto", "skip", "from", "with", "probability", "sim", "init", "initial", "final", "clamp", "except", "true", "false", "int", "double", "prob", "bool", "min", "max"])
# Names afsmc itself generates in its outputs.
GENERATED = frozenset({"mode"})

# Names of constants, variables, formulas, actions and the machine (PRISM's module).
RESERVED = PRISM_KEYWORDS | STORM_KEYWORDS | STORM_PROPERTY_WORDS | GENERATED
# Names PRISM quotes: reward structures, and labels ("init" and "deadlock" are PRISM's own).
QUOTED_RESERVED = PRISM_KEYWORDS | STORM_KEYWORDS
LABEL_RESERVED = QUOTED_RESERVED | {"deadlock"}


def safe_identifier(text: str) -> str:
    """A name every backend accepts, made from any text (a file name): ASCII letters,
    digits and '_', starting with a letter, and not reserved."""
    clean = "".join(ch if (ch.isascii() and ch.isalnum()) or ch == "_" else "_" for ch in text)
    if not clean[:1].isalpha() or clean in RESERVED:
        clean = f"m_{clean}"
    return clean


def suggest(name: str, candidates: Iterable[str]) -> str | None:
    close = difflib.get_close_matches(name, sorted(set(candidates)), n=1, cutoff=0.6)
    return close[0] if close else None


def did_you_mean(name: str, candidates: Iterable[str]) -> str | None:
    best = suggest(name, candidates)
    return f"did you mean '{best}'?" if best else None
