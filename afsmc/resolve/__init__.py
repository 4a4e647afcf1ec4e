"""Stage 2: the AST resolved into the typed IR (names bound, constants evaluated, types checked).

`resolve(module, overrides)` returns a `Resolved`: the `ir.Model` and what resolving
learnt beside it (warnings, the names the source uses). The modules split the work by
concern: names (namespaces, reserved names, lookups), constants (values, intervals,
--const), declarations (modes, variables, formulas), expressions (building and typing),
actions (actions, hazards, updates, weight cycles), properties (labels, rewards,
queries); `base` holds their shared state and `resolver` runs them in order.
"""

from afsmc.resolve.constants import parse_override
from afsmc.resolve.resolver import Resolved, resolve

__all__ = ["Resolved", "parse_override", "resolve"]
