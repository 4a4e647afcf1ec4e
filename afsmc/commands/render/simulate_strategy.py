"""`afsmc simulate --strategy min:NAME|max:NAME`: the line that says which Storm strategy
the runs followed (the API's :func:`afsmc.api.simulate.prepare` extracts it)."""

from __future__ import annotations

from afsmc.text import num
from afsmc.verify.core.policy import Policy


def followed_text(policy: Policy | None) -> None:
    if policy is not None:
        print(f"the runs followed Storm's {policy.direction} strategy of {policy.property} "
              f"(its choice in {len(policy.states):,} states); Storm's {policy.direction}: "
              f"{num(policy.value)}")
