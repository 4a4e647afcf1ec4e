"""`afsmc simulate --strategy min:NAME|max:NAME`: the runs follow Storm's scheduler."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from typing import Any

from afsmc.commands.common import usage_error
from afsmc.sim.policy import Table
from afsmc.sim.run import Job, program
from afsmc.text import num
from afsmc.verify.policy import Policy, extract


def follow(job: Job, args: argparse.Namespace) -> tuple[Job, Policy | None]:
    """The job whose runs follow the strategy `args.strategy`, extracted by Storm (no
    --strategy: the job as it is)."""
    if not args.strategy:
        return job, None
    if args.resolve != "uniform":
        usage_error("--strategy resolves the interval constants itself: give it or "
                    "--resolve, not both")
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


def followed_text(policy: Policy | None) -> None:
    if policy is not None:
        print(f"the runs followed Storm's {policy.direction} strategy of {policy.property} "
              f"(its choice in {len(policy.states):,} states); Storm's {policy.direction}: "
              f"{num(policy.value)}")
