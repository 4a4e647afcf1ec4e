"""Successor generation compiled from a model's lowered commands (numba): one kernel per
model, generated as Python source from the folded guards, probabilities and updates that
afsmc.verify.explorer.explore.compile_model keeps, whose numpy counterpart is that
module's `expand` (the reference the tests compare this against, bit for bit).

The kernel walks the states a mode at a time and, for each of the mode's commands (in
the explorer's order), evaluates the guard in every state, then the branches'
probabilities and updated keys in those where it holds, and merges equal successors /
drops zero probabilities exactly as `_merge` does (whose choice of order depends on the
whole batch: kept when no row of the command has a zero or two equal successors and it
has at most 4 branches, else sorted by successor). It writes the choices in the order the
numpy path concatenates them, and the caller sorts them by state (`_ordered`) as before.

Every operator is translated with afsmc.model.kernel's semantics (int64 integers, `/`
real division, Storm's `mod`, `==` of doubles within TOLERANCE, the C library's `pow`).
Where the numpy path would see an undefined or unusual value (a division or `mod` by
zero, `floor` of a non-finite value, an integer `pow` with a negative exponent, a NaN in
`min`/`max`), a variable leaving its range or probabilities not summing to 1, the kernel
stops and the caller runs the numpy path on the same states, which computes the reference
answer (or raises its GiveUp). A model with an expression not translated here, reward
structures or further valuations of the interval probabilities is not compiled at all.
"""

from __future__ import annotations

import hashlib
import importlib.util
import math
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from afsmc.model import expr as E
from afsmc.model.kernel import TOLERANCE

I64 = npt.NDArray[np.int64]
F64 = npt.NDArray[np.float64]

OK, FALLBACK, FULL = 0, 1, 2  # the kernel's status: done, ask numpy, outputs too small
SUM_TOLERANCE = 1e-6  # as afsmc.verify.explorer.explore's check of a distribution
MERGE_KEPT_MAX = 4  # _merge keeps the branches' order up to this many branches


class Untranslatable(Exception):
    """An expression this module does not translate: the model keeps the numpy path."""


@dataclass(frozen=True)
class Raw:
    """The kernel's choices in the numpy path's order, before they are sorted by state:
    choice -> state (index into the keys) and command; branch -> its choice, successor
    key and probability."""

    state: I64
    command: npt.NDArray[np.int32]
    row: I64
    target: I64
    prob: F64
    rewards: list[F64]  # per reward structure asked: the action reward per choice


class _Emitter:
    """Statements of the kernel's source, each subexpression evaluated into a temporary
    (eagerly, as the numpy path evaluates every operand)."""

    def __init__(self, names: dict[str, str]) -> None:
        self.names = names  # a state variable (and "mode") -> its decoded local
        self.lines: list[str] = []
        self.count = 0
        self.memo: dict[E.Expr, str] = {}  # within one loop: a subexpression's temporary

    def temp(self, indent: str, code: str) -> str:
        name = f"t{self.count}"
        self.count += 1
        self.lines.append(f"{indent}{name} = {code}")
        return name

    def stop(self, indent: str, cond: str) -> None:
        self.lines.append(f"{indent}if {cond}:")
        self.lines.append(f"{indent}    return -1")

    def expr(self, e: E.Expr, ind: str) -> str:
        if e not in self.memo:
            self.memo[e] = self._expr(e, ind)
        return self.memo[e]

    def _expr(self, e: E.Expr, ind: str) -> str:
        if isinstance(e, E.Lit):
            return _literal(e)
        if isinstance(e, E.ModeVal):
            return str(int(e.number))
        if isinstance(e, (E.VarRef, E.CurrentMode)):
            name = "mode" if isinstance(e, E.CurrentMode) else e.name
            if name not in self.names:
                raise Untranslatable(f"the variable {name}")
            return self.names[name]
        if isinstance(e, E.Unary):
            a = self.expr(e.operand, ind)
            if e.op == "-":
                return self.temp(ind, f"-{a}")
            if e.op == "!":
                return self.temp(ind, f"not {a}")
        if isinstance(e, E.Binary):
            return self._binary(e, ind)
        if isinstance(e, E.Ite):
            c, a, b = (self.expr(x, ind) for x in (e.cond, e.then, e.other))
            if e.type is E.Type.DOUBLE:
                a, b = f"float({a})", f"float({b})"
            return self.temp(ind, f"{a} if {c} else {b}")
        if isinstance(e, E.Call):
            return self._call(e, ind)
        raise Untranslatable(type(e).__name__)

    def _binary(self, e: E.Binary, ind: str) -> str:
        a, b = self.expr(e.left, ind), self.expr(e.right, ind)
        double = E.Type.DOUBLE in (e.left.type, e.right.type)
        if e.op in ("+", "-", "*"):
            if E.Type.BOOL in (e.left.type, e.right.type):
                raise Untranslatable("arithmetic on booleans")
            return self.temp(ind, f"{a} {e.op} {b}")
        if e.op == "/":
            self.stop(ind, f"{b} == 0")
            return self.temp(ind, f"float({a}) / float({b})")
        if e.op in ("==", "!="):
            same = f"({a} == {b})"
            if double:
                same = f"({a} == {b} or abs(float({a}) - float({b})) <= {TOLERANCE!r})"
            return self.temp(ind, same if e.op == "==" else f"not {same}")
        if e.op in ("<", "<=", ">", ">="):
            return self.temp(ind, f"{a} {e.op} {b}")
        if e.op in ("&&", "||", "=>"):
            code = {"&&": f"{a} and {b}", "||": f"{a} or {b}", "=>": f"(not {a}) or {b}"}
            return self.temp(ind, code[e.op])
        raise Untranslatable(f"the operator {e.op}")

    def _call(self, e: E.Call, ind: str) -> str:
        args = [self.expr(x, ind) for x in e.args]
        if e.func in ("min", "max"):
            if e.type is E.Type.DOUBLE:
                args = [f"float({a})" for a in args]
                for a in args:
                    self.stop(ind, f"{a} != {a}")  # NaN: numpy's minimum propagates it
            return self.temp(ind, f"{e.func}({', '.join(args)})")
        if e.func in ("floor", "ceil") and len(args) == 1:
            x = self.temp(ind, f"float({args[0]})")
            self.stop(ind, f"not (abs({x}) < 9.2e18)")  # NaN, infinite or beyond int64
            return self.temp(ind, f"np.int64(math.{e.func}({x}))")
        if e.func == "pow" and len(args) == 2:
            if e.type is E.Type.INT:
                self.stop(ind, f"{args[1]} < 0")  # a fraction in the numpy path
                return self.temp(ind, f"_ipow(np.int64({args[0]}), np.int64({args[1]}))")
            return self.temp(ind, f"math.pow(float({args[0]}), float({args[1]}))")
        if e.func == "mod" and len(args) == 2:
            a, b = args
            self.stop(ind, f"{b} == 0")
            if all(x.type is E.Type.INT for x in e.args):
                return self.temp(ind, f"_imod(np.int64({a}), np.int64({b}))")
            return self.temp(ind, f"_fmod(float({a}), float({b}))")
        raise Untranslatable(f"the function {e.func}")


def _literal(e: E.Lit) -> str:
    if e.type is E.Type.BOOL or isinstance(e.value, bool):
        return "True" if e.value else "False"
    if e.type is E.Type.DOUBLE or isinstance(e.value, float):
        v = float(e.value)
        if not math.isfinite(v):
            raise Untranslatable("a non-finite literal")
        return repr(v)
    return f"np.int64({int(e.value)})"


HEADER = '''"""Generated by afsmc.verify.kernels.successors: do not edit."""
import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def _ipow(b, k):
    out = np.int64(1)
    for _ in range(k):
        out = out * b
    return out


@numba.njit(cache=True, nogil=True)
def _imod(a, b):
    r = abs(a) % abs(b)
    if a >= 0:
        return r
    return b - r


@numba.njit(cache=True, nogil=True)
def _fmod(a, b):
    r = np.fmod(a, b)
    if a >= 0:
        return r
    return r + b


@numba.njit(cache=True, nogil=True)
def _emit(r, k, kept, sel, tks, prs, cmd, choices, nb, o_state, o_row, o_tk, o_pr, o_cmd, order):
    """Row r of a command's batch: its merged branches from nb on (the count after)."""
    o_state[choices + r] = sel[r]
    o_cmd[choices + r] = cmd
    if kept:
        for j in range(k):
            o_row[nb] = choices + r
            o_tk[nb] = tks[r, j]
            o_pr[nb] = prs[r, j]
            nb += 1
        return nb
    for j in range(k):
        order[j] = j
    for j in range(1, k):  # a stable insertion sort by successor
        x = order[j]
        i = j - 1
        while i >= 0 and tks[r, order[i]] > tks[r, x]:
            order[i + 1] = order[i]
            i -= 1
        order[i + 1] = x
    last = -1
    for j in range(k):
        p = prs[r, order[j]]
        if p == 0:
            continue
        t = tks[r, order[j]]
        if last >= 0 and o_tk[last] == t:
            o_pr[last] += p
            continue
        o_row[nb] = choices + r
        o_tk[nb] = t
        o_pr[nb] = p
        last = nb
        nb += 1
    return nb


@numba.njit(cache=True, nogil=True)
def _batch(cnt, k, cmd, sel, tks, prs, rws, choices, nb, o_state, o_row, o_tk, o_pr, o_cmd,
           o_rw, perm):
    """A command's batch of `cnt` rows written out: (status, choices, branches)."""
    if choices + cnt > len(o_state) or nb + cnt * k > len(o_tk):
        return FULL, choices, nb
    kept = _kept(cnt, k, tks, prs)
    for r in range(cnt):
        nb = _emit(r, k, kept, sel, tks, prs, cmd, choices, nb, o_state, o_row, o_tk, o_pr,
                   o_cmd, perm)
        for i in range(o_rw.shape[0]):
            o_rw[i, choices + r] = rws[r, i]
    return 0, choices + cnt, nb


@numba.njit(cache=True, nogil=True)
def _kept(cnt, k, tks, prs):
    """Whether _merge keeps the batch's branches in their order."""
    if k > KEPT_MAX:
        return False
    for r in range(cnt):
        for j in range(k):
            if prs[r, j] == 0:
                return False
            for i in range(j + 1, k):
                if tks[r, i] == tks[r, j]:
                    return False
    return True

'''


def source(c: Any) -> str:
    """The kernel's module source for the explorer's Compiled model `c` (Untranslatable
    where it cannot be): a function per command (its batch's rows, -1 where the numpy
    path must decide) and `expand`, which calls them mode by mode."""
    if c.at is not None:
        raise Untranslatable("further valuations of the interval probabilities")
    fields = list(c.layout.fields.values())
    names = {f.name: f"v{i}" for i, f in enumerate(fields)}
    decode = []
    for f, v in zip(fields, names.values(), strict=True):
        bits = f"((key >> {f.shift}) & {f.mask})"
        decode.append(f"{v} = {bits} != 0" if f.boolean else f"{v} = {bits} + {f.lo}")
    em = _Emitter(names)
    body = ["@numba.njit(cache=True, nogil=True)",
            "def expand(keys, order, starts, ends, group_mode, sel, tks, prs, rws,",
            "           o_state, o_row, o_tk, o_pr, o_cmd, o_rw):",
            "    choices = 0",
            "    nb = 0",
            "    perm = np.empty(tks.shape[1], np.int64)",
            "    for g in range(len(starts)):",
            "        md = group_mode[g]",
            "        a = starts[g]",
            "        b = ends[g]"]
    for mode, cmds in sorted(c.modes.items()):
        if not cmds:
            continue
        body += [f"        if md == {int(mode)}:", "            cnt = -1"]
        last = None
        for cmd in cmds:
            name = _command(em, cmd, decode)
            # the previous command's guard (a floor/ceil variant's): its states in `sel`
            known = "cnt" if last is not None and cmd.guard_key == last else "-1"
            last = cmd.guard_key
            body += [f"            cnt = {name}(keys, order, a, b, sel, {known}, tks, prs, rws)",
                     "            if cnt < 0:",
                     f"                return {FALLBACK}, 0, 0",
                     f"            status, choices, nb = _batch(cnt, {len(cmd.branches)}, "
                     f"{cmd.index}, sel, tks, prs, rws, choices, nb,",
                     "                                         o_state, o_row, o_tk, o_pr, "
                     "o_cmd, o_rw, perm)",
                     f"            if status != {OK}:",
                     "                return status, 0, 0"]
    body.append(f"    return {OK}, choices, nb")
    header = HEADER.replace("KEPT_MAX", str(MERGE_KEPT_MAX)).replace("FULL", str(FULL))
    return header + "\n".join(em.lines) + "\n\n" + "\n".join(body) + "\n"


def _command(em: _Emitter, cmd: Any, decode: list[str]) -> str:
    """The function of one command's batch (its name): the states of `order[a:b]` where
    its guard holds into `sel`, their branches' probabilities, successors and action
    rewards into `tks`, `prs`, `rws`; their count, or -1. `known` >= 0: the guard is the
    previous command's, whose `known` states are in `sel` already."""
    out, ind = em.lines, " " * 8
    if cmd.guard_expr is None or cmd.reward_exprs is None \
            or any(b.source is None for b in cmd.branches):
        raise Untranslatable("a command compiled without its expressions")
    k, name = len(cmd.branches), f"command{cmd.index}"
    out += ["@numba.njit(cache=True, nogil=True)",
            f"def {name}(keys, order, a, b, sel, known, tks, prs, rws):",
            "    cnt = known",
            "    if known < 0:",
            "        cnt = 0",
            "    for t in range(a if known < 0 else b, b):",
            "        i = order[t]",
            "        key = keys[i]"]
    out += [ind + d for d in decode]
    em.memo.clear()
    g = em.expr(cmd.guard_expr, ind)
    out += [f"{ind}if {g}:", f"{ind}    sel[cnt] = i", f"{ind}    cnt += 1",
            "    for r in range(cnt):",
            "        key = keys[sel[r]]"]
    out += [ind + d for d in decode]
    em.memo.clear()
    for j, br in enumerate(cmd.branches):
        prob, values = br.source
        p = em.expr(prob, ind)
        out.append(f"{ind}prs[r, {j}] = float({p})")
        tk = em.temp(ind, f"(key & ~{br.clear}) | {br.bits}" if br.clear else "key")
        for (f, _, check), value in zip(br.updates, values, strict=True):
            new = em.expr(value, ind)
            if f.boolean:
                tk = em.temp(ind, f"({tk} & ~{1 << f.shift}) | (np.int64({new}) << {f.shift})")
                continue
            if value.type is not E.Type.INT:
                raise Untranslatable(f"{f.name} updated to a non-integer")
            if check:
                em.stop(ind, f"{new} < {f.lo} or {new} >= {f.lo + f.size}")
            tk = em.temp(ind, f"{tk} + ({new} - {em.names[f.name]}) * {f.stride}")
        out.append(f"{ind}tks[r, {j}] = {tk}")
    for i, rw in enumerate(cmd.reward_exprs):
        value = "0.0" if rw is None else f"float({em.expr(rw, ind)})"
        out.append(f"{ind}rws[r, {i}] = {value}")
    total = " + ".join(f"prs[r, {j}]" for j in range(k))
    em.stop(ind, f"not abs(({total}) - 1.0) <= {SUM_TOLERANCE!r}")
    out += ["    return cnt", "", ""]
    return name


def cache_dir() -> str:
    """Where generated kernels (and numba's cache of them) live: AFSMC_KERNEL_CACHE, or
    afsmc/kernels under the user's cache directory."""
    env = os.environ.get("AFSMC_KERNEL_CACHE")
    if env:
        return env
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "afsmc", "kernels")


def load(text: str) -> Callable[..., tuple[int, int, int]]:
    """The `expand` function of the generated module `text`, written to a file named by
    its hash (so numba's on-disk cache finds it again in the next process)."""
    digest = hashlib.sha256(text.encode()).hexdigest()[:24]
    name = f"afsmc_successors_{digest}"
    if name in sys.modules:
        return sys.modules[name].expand  # type: ignore[no-any-return]
    folder = cache_dir()
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, name + ".py")
    if not os.path.exists(path):
        tmp = f"{path}.{os.getpid()}.tmp"
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, path)  # atomic: another process may write the same file
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[name] = module
    return module.expand  # type: ignore[no-any-return]


def kernel(c: Any) -> Callable[..., tuple[int, int, int]] | None:
    """The compiled successor kernel of `c` (None: not translated), built once per model."""
    if c.successors is None:
        try:
            c.successors = load(source(c))
        except Untranslatable:
            c.successors = False
    return c.successors or None


# Choices and branches per state seen by each kernel (by id), for the capacity of the
# next call's outputs (a call that fills them runs again with twice as much)
_RATIO: dict[int, tuple[float, float]] = {}
RATIO_FROM = 1000  # from this many states on, a call's counts are taken as typical


def run(fn: Callable[..., tuple[int, int, int]], keys: I64, order: I64, starts: I64,
        ends: I64, group_mode: I64, branches: int, rewards: int) -> Raw | None:
    """The raw choices of `keys` (grouped by mode: `order`, `starts`, `ends`,
    `group_mode`); None where the numpy path must decide. `branches`: the most branches
    of a command; `rewards`: the number of reward structures asked."""
    n = len(keys)
    sel = np.empty(n, np.int64)
    tks = np.empty((n, max(branches, 1)), np.int64)
    prs = np.empty((n, max(branches, 1)))
    rws = np.empty((n, max(rewards, 1)))
    per_c, per_b = _RATIO.get(id(fn), (2.0, 4.0))
    cap_c, cap_b = int(per_c * n) + 16, int(per_b * n) + 64
    while True:
        o_state, o_cmd = np.empty(cap_c, np.int64), np.empty(cap_c, np.int32)
        o_row, o_tk, o_pr = np.empty(cap_b, np.int64), np.empty(cap_b, np.int64), np.empty(cap_b)
        o_rw = np.empty((rewards, cap_c))
        status, nc, nb = fn(keys, order, starts, ends, group_mode, sel, tks, prs, rws,
                            o_state, o_row, o_tk, o_pr, o_cmd, o_rw)
        if status == OK:
            if n >= RATIO_FROM:  # the next call's capacities: this one's counts, and a margin
                _RATIO[id(fn)] = (max(per_c, 1.25 * nc / n), max(per_b, 1.25 * nb / n))
            return Raw(o_state[:nc], o_cmd[:nc], o_row[:nb], o_tk[:nb], o_pr[:nb],
                       [o_rw[i, :nc] for i in range(rewards)])
        if status == FALLBACK:
            return None
        cap_c, cap_b = 2 * cap_c, 2 * cap_b
