"""Stage 4: the checked model lowered to plain guarded commands, then reduced exactly.

`lowering.lower(model, resolution) -> Lowered` turns weights, hazards and interval constants
into guarded commands with complete guards; `reduce.reduce(lowered, reductions) -> Lowered`
applies the exact state-space reductions. Every backend and the simulator read `Lowered`.
"""
