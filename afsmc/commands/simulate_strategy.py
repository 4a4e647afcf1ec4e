"""`afsmc simulate --strategy min:NAME|max:NAME`: the runs follow Storm's scheduler."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from typing import Any

from afsmc.sim.policy import Table
from afsmc.sim.run import Job, program
from afsmc.text import num
from afsmc.verify.policy import Policy, extract


def follow(job: Job, args: argparse.Namespace) -> tuple[Job, Policy]:
    """The job whose runs follow the strategy `args.strategy`, extracted by Storm."""
    model = program(job).model

    def say(text: str) -> None:
        if not args.json:
            print(f"simulate: {text}", file=sys.stderr)

    policy = extract(model, args.strategy, progress=say)
    table = Table(f"{policy.direction}:{policy.property}", policy.variables, policy.states,
                  policy.commands)
    return dataclasses.replace(job, policy=table), policy


def followed_json(policy: Policy | None) -> dict[str, Any]:
    if policy is None:
        return {}
    return {"strategy": {"property": policy.property, "direction": policy.direction,
                         "value": policy.value, "states": len(policy.states)}}


def followed_text(policy: Policy) -> str:
    return (f"the runs followed Storm's {policy.direction} strategy of {policy.property} "
            f"(its choice in {len(policy.states):,} states); Storm's {policy.direction}: "
            f"{num(policy.value)}")
