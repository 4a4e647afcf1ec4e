"""W305: mode numbers spread over a wide range.

`mode` is one integer variable in the PRISM and JANI output, declared over the range of
the mode numbers. Storm's symbolic engines (hybrid and dd, which `verify --engine auto`
picks for large models) build in time that grows with a variable's range, not with the
values it takes: a two-mode machine numbered 0 and 1000000 did not build in a minute
(10,000: 6 s; 100,000: 28 s; measured with stormpy 2.0). The sparse engine is unaffected.
"""

from __future__ import annotations

from afsmc.diagnostics import Reporter, codes
from afsmc.model import ir

# A span this wide costs Storm's symbolic build seconds; the paper's UAV spans 17.
WIDE = 10_000


def check_mode_numbers(model: ir.Model, rep: Reporter) -> None:
    numbers = sorted(m.number for m in model.modes)
    if not numbers or numbers[-1] - numbers[0] + 1 <= WIDE:
        return
    wide = max(model.modes, key=lambda m: m.number)
    rep.warning(codes.W305, f"the mode numbers span {numbers[-1] - numbers[0] + 1:,} values for "
                f"{len(numbers)} modes: Storm's symbolic engines (hybrid, dd; verify's "
                "choice for large models) build in time that grows with that span",
                wide.span, hint="number the modes densely (e.g. 0, 1, 2, ...), or leave the "
                "numbers out; the sparse engine is not affected")
