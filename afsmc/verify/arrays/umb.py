"""Storm's sparse model as numpy arrays, through its binary export (UMB: the matrix,
labels, rewards and choice labels as flat arrays in an uncompressed archive): what the
backward pass (afsmc.verify.arrays.acyclic) and the strategies' arrays
(afsmc.verify.engines.strategy_arrays) read of a model Storm built. Runs inside the Storm
process."""

from __future__ import annotations

import itertools
import json
import os
import shutil
import tarfile
import tempfile
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.verify.arrays.acyclic import (
    LABEL,
    Arrays,
    Plan,
    Vec,
    layers_of,
    renumber,
    self_loops,
)

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]
Bools = npt.NDArray[np.bool_]
Idx = npt.NDArray[np.int32]  # state numbers (a model of 2^31 states or branches is Storm's)

READ_CHUNK = 1 << 22  # entries converted at a time while reading (bounds the temporaries)


def _member(tar: tarfile.TarFile, path: str, name: str, dtype: Any, count: int,
            into: Any = None) -> npt.NDArray[Any] | None:
    """The array stored as `name`, read as `dtype`; converted to `into` a slice at a time
    (the unsigned 64-bit offsets and targets of the export as int64 and int32)."""
    try:
        info = tar.getmember(name)
    except KeyError:
        return None
    if into is None:
        return np.fromfile(path, dtype=dtype, count=count, offset=info.offset_data)
    out = np.empty(count, into)
    size = np.dtype(dtype).itemsize
    for i in range(0, count, READ_CHUNK):
        k = min(READ_CHUNK, count - i)
        out[i:i + k] = np.fromfile(path, dtype=dtype, count=k,
                                   offset=info.offset_data + i * size)
    return out


def _bits(tar: tarfile.TarFile, path: str, name: str, n: int) -> Bools | None:
    raw = _member(tar, path, name, np.uint8, (n + 63) // 64 * 8)
    if raw is None:
        return None
    return np.unpackbits(raw, bitorder="little")[:n].astype(bool)


def _annotations(index: dict[str, Any], group: str) -> dict[str, tuple[str, Any]]:
    """alias -> (the folder name in the archive, its description)."""
    found = index.get("annotations", {}).get(group, {})
    return {str(v.get("alias", k)): (k, v) for k, v in found.items()}


@dataclass
class Raw:
    """The model as exported, before layering."""

    states: I64
    choices: I64
    target: Idx
    prob: F64
    initial: int
    labels: dict[str, Bools]
    state_rewards: dict[str, list[tuple[str, F64]]]  # name -> (applies-to, values)
    actions: npt.NDArray[np.uint32] | None = None  # these three: a strategy's, as in Arrays
    action_names: list[str] = field(default_factory=list)
    packed: dict[str, npt.NDArray[np.uint8]] | None = None


def read_umb(path: str, labels: list[str], rewards: list[str],
             packed: tuple[str, ...] | None = None) -> Raw | None:
    """The arrays of a UMB archive (uncompressed, doubles); None if it is not of that form.
    `packed`: labels read as they are stored (8 states a byte), with each choice's action:
    what a strategy's extraction needs."""
    with tarfile.open(path) as tar:
        index = json.loads(tar.extractfile("index.json").read())  # type: ignore[union-attr]
        ts = index["transition-system"]
        if ts.get("branch-probability-type", {}).get("type") != "double":
            return None
        n, m, b = int(ts["#states"]), int(ts["#choices"]), int(ts["#branches"])
        if max(n, b) >= 2**31:
            return None
        states = _member(tar, path, "state-to-choices.bin", np.uint64, n + 1, np.int64)
        if states is None:  # a DTMC may leave out its trivial choices
            states = np.arange(n + 1, dtype=np.int64)
        choices = _member(tar, path, "choice-to-branches.bin", np.uint64, m + 1, np.int64)
        target = _member(tar, path, "branch-to-target.bin", np.uint64, b, np.int32)
        prob = _member(tar, path, "branch-to-probability.bin", np.float64, b)
        initial = _bits(tar, path, "state-is-initial.bin", n)
        if choices is None or target is None or prob is None or initial is None:
            return None
        aps = _annotations(index, "aps")
        found = {x: _bits(tar, path, f"annotations/aps/{aps[x][0]}/states/values.bin", n)
                 for x in labels if x in aps}
        rws = _annotations(index, "rewards")
        rw: dict[str, list[tuple[str, F64]]] = {}
        for x in rewards:
            key = x if x in rws else (next(iter(rws)) if x == "" and len(rws) == 1 else None)
            if key is None:
                return None
            folder, desc = rws[key]
            size = {"states": n, "choices": m}  # transition rewards: left to Storm
            rw[x] = []
            for where in desc.get("applies-to", []):
                if where not in size:
                    return None
                vals = _member(tar, path, f"annotations/rewards/{folder}/{where}/values.bin",
                               np.float64, size[where])
                if vals is None or desc.get("type", {}).get("type") != "double":
                    return None
                rw[x].append((where, vals))
        extra = None if packed is None else _extra(tar, path, index, packed, n, m)
    if any(v is None for v in found.values()) or len(found) < len(labels) or (
            packed is not None and extra is None):
        return None
    out = Raw(states, choices, target, prob,
              int(np.flatnonzero(initial)[0]), {k: v for k, v in found.items()
                                                if v is not None}, rw)
    if extra is not None:
        out.packed, out.actions, out.action_names = extra
    return out


def _extra(tar: tarfile.TarFile, path: str, index: dict[str, Any], packed: tuple[str, ...],
           n: int, m: int) -> tuple[dict[str, npt.NDArray[np.uint8]], npt.NDArray[np.uint32],
                                    list[str]] | None:
    """The labels `packed`, as stored, and each choice's action with the actions' names
    (an archive without actions: every choice unlabelled)."""
    aps = _annotations(index, "aps")
    bits = {}
    for x in packed:
        raw = None if x not in aps else _member(
            tar, path, f"annotations/aps/{aps[x][0]}/states/values.bin", np.uint8,
            (n + 63) // 64 * 8)
        if raw is None:
            return None
        bits[x] = raw
    actions = _member(tar, path, "actions/choices/values.bin", np.uint32, m)
    if actions is None:
        return bits, np.zeros(m, np.uint32), [""]
    offsets = _member(tar, path, "actions/choices/string-mapping.bin", np.uint64,
                      int(index["transition-system"].get("#choice-actions", 0)) + 1)
    member = tar.extractfile("actions/choices/strings.bin")
    if offsets is None or member is None:
        return None
    text = member.read().decode("utf-8")
    names = [text[int(a):int(b)] for a, b in itertools.pairwise(offsets.tolist())]
    return bits, actions, names


def export(stormpy: Any, model: Any, p: Plan, folder: str) -> str:
    """Label each target's states in Storm's model and write it as an uncompressed UMB
    archive in `folder`; the archive's path."""
    from stormpy.developer import storage

    for i, formula in enumerate(p.targets):
        states = stormpy.model_checking(model, formula).get_truth_values_vector()
        name = LABEL + str(i)
        if not model.labeling.contains_label(name):
            model.labeling.add_label(name)
        model.labeling.set_states(name, states)
    options = storage.UmbExportOptions()
    options.compression = storage.CompressionMode.NO_COMPRESSION
    umb = storage.sparse_model_to_umb(model, options)
    path = os.path.join(folder, "model.umb")
    storage.to_archive(umb, path, options)
    del umb
    return path


def read(stormpy: Any, model: Any, p: Plan, packed: tuple[str, ...] | None = None) -> Raw | None:
    """Storm's sparse `model`, with the plan's targets, as arrays; None if Storm's export
    is not of the expected form. `packed`: see :func:`read_umb`."""
    folder = tempfile.mkdtemp(prefix="afsmc-acyclic-")
    try:
        path = export(stormpy, model, p, folder)
        return read_umb(path, [LABEL + str(i) for i in range(len(p.targets))],
                        sorted({q.reward for q in p.queries if q.kind == "R"}), packed)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def arrange(raw: Raw) -> Arrays | None:
    """Layer and renumber the exported model; None if it has a cycle (other than
    self-loops) or a transition of probability 0."""
    if (raw.prob <= 0).any():
        return None
    layers = layers_of(raw.states, raw.choices, raw.target)
    if layers is None:
        return None
    perm = np.concatenate(layers)
    bounds = np.zeros(len(layers) + 1, np.int64)
    np.cumsum([len(x) for x in layers], out=bounds[1:])
    del layers
    states, choices, old_choice, target, prob, inv = renumber(
        raw.states, raw.choices, raw.target, raw.prob, perm)
    raw.target, raw.prob = np.zeros(0, np.int32), np.zeros(0)  # freed
    rewards: dict[str, Vec] = {}
    for name, parts in raw.state_rewards.items():
        per_choice = np.zeros(len(choices) - 1)
        for where, vals in parts:
            if where == "states":
                per_choice += np.repeat(vals[perm], np.diff(states))
            else:
                per_choice += vals[old_choice]
        rewards[name] = per_choice
    labels = {k: v[perm] for k, v in raw.labels.items()}
    stay = self_loops(states, choices, target, prob)
    out = Arrays(states, choices, target, prob, stay, bounds, int(inv[raw.initial]),
                 labels, rewards)
    if raw.packed is not None and raw.actions is not None:
        out.order, out.actions, out.action_names = perm, raw.actions[old_choice], raw.action_names
        out.packed, raw.packed, raw.actions = raw.packed, None, None
    del perm, old_choice
    return out


def prepare(stormpy: Any, model: Any, p: Plan) -> Arrays | None:
    """The layered arrays of Storm's sparse `model`; None if it has cycles (or Storm's
    export is not of the expected form)."""
    raw = read(stormpy, model, p)
    return None if raw is None else arrange(raw)
