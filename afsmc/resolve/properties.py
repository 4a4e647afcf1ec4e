"""Properties and what they read: labels, reward structures (E248), the P and R queries
with their step bounds (E241, E242, E247), and property names that clash with the queries
afsmc asks for them (E244).
"""

from __future__ import annotations

import math

from afsmc.diagnostics import Related, codes
from afsmc.model import expr as E
from afsmc.model import ir
from afsmc.model.evaluate import EvalError, scalar
from afsmc.model.expr import Type
from afsmc.model.names import did_you_mean
from afsmc.resolve.base import Ctx, ResolverBase
from afsmc.syntax import ast
from afsmc.syntax.scan import flat_text, tokens

_PROPERTY = Ctx("a property", labels=True)


class PropertiesMixin(ResolverBase):
    def _label_decl(self, d: ast.LabelDecl) -> ir.Label:
        return ir.Label(d.name.text, self._bool(d.value, Ctx("a label")), d.span)

    def _rewards(self, d: ast.RewardsDecl) -> ir.RewardStruct:
        items = []
        for it in d.items:
            if it.action is not None and it.action.text not in self.action_names:
                self.rep.error(codes.E203, f"'{it.action.text}' is not an action", it.action.span,
                               hint=did_you_mean(it.action.text, self.action_names))
            elif it.action is not None and it.action.text in self.branch_hazards:
                self.rep.error(codes.E248, f"an action reward cannot name the probabilistic hazard "
                               f"'{it.action.text}': it is a branch of every action of its "
                               "modes, and an action reward counts whole actions",
                               it.action.span, hint="reward the hazard's target mode with a state "
                               "reward, e.g. 'mode == Target : 1'")
            guard = self._bool(it.guard, Ctx("a reward's condition"))
            value = self._num(it.value, Ctx("a reward"))
            items.append(ir.RewardItem(it.action.text if it.action else None, guard, value, it.span))
        return ir.RewardStruct(d.name.text, tuple(items), d.span)

    def _check_query_names(self, props: list[ir.Property]) -> None:
        """An MDP asks `P=? [...]` of property `a` as the queries `a_min` and `a_max`: a
        property of that name would share its query, and one of the two values be wrong."""
        asked = {f"{p.name}_{o}": p for p in props if not p.opt for o in ("min", "max")}
        for p in props:
            if p.name in asked:
                other = asked[p.name]
                self.rep.error(
                    codes.E244, f"property {p.name} has the name of a query of property "
                    f"{other.name}: with interval constants afsmc asks {other.name} as "
                    f"{other.name}_min and {other.name}_max", p.span,
                    hint="rename one of them", related=[Related(f"property {other.name}",
                                                                other.span)])

    def _property(self, d: ast.PropertyDecl) -> ir.Property:
        q = d.query
        if isinstance(q, ast.PQuery):
            p = q.path
            path: ir.Path
            if isinstance(p, ast.Eventually):
                path = ir.Path("F", self._bool(p.target, _PROPERTY), bound=self._step_bound(p.bound))
            elif isinstance(p, ast.Globally):
                # Storm has no step-bounded G; afsmc.verify asks 1 - P[F<=k !phi] for it.
                path = ir.Path("G", self._bool(p.target, _PROPERTY), bound=self._step_bound(p.bound))
            elif isinstance(p, ast.Until):
                path = ir.Path("U", self._bool(p.right, _PROPERTY), self._bool(p.left, _PROPERTY),
                               self._step_bound(p.bound))
            else:
                path = ir.Path("X", self._bool(p.target, _PROPERTY))
            opt = {"P": "", "Pmin": "min", "Pmax": "max"}[q.op]
            return ir.Property(d.name.text, "P", opt, path, None, d.span,  # type: ignore[arg-type]
                               *_written(q), threshold=self._threshold(q, opt))
        return self._reward_property(d, q)

    def _threshold(self, q: ast.PQuery | ast.RQuery, opt: str) -> ir.Threshold | None:
        """`P>=0.65 [ ... ]`: a constant number, within [0, 1] for a probability, on a
        query without min or max (the verdict judges the min and the max itself)."""
        t = q.threshold
        if t is None:
            return None
        kind = "P" if isinstance(q, ast.PQuery) else "R"
        if opt:
            self.rep.error(codes.E251, f"a requirement cannot name {kind}{opt}: it is judged "
                           "over every resolution of the interval constants, by the min and "
                           "the max together", q.span,
                           hint=f"write {kind}{t.op}... without '{opt}' (holds: the worst "
                           f"case meets it), or {kind}{opt}=? [ ... ] for the value")
            return None
        x = self._expr(t.value, Ctx("a threshold", state=False))
        if x.type not in (Type.INT, Type.DOUBLE):
            self.rep.error(codes.E252, "a threshold must be a number", t.value.span)
            return None
        try:
            v = scalar(x, self._const_env())
        except (EvalError, ArithmeticError) as exc:
            self.rep.error(codes.E252, f"a threshold must be a finite number: {exc}",
                           t.value.span)
            return None
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            self.rep.error(codes.E252, f"a threshold must be a finite number, not {v}",
                           t.value.span)
            return None
        if kind == "P" and not 0 <= v <= 1:
            self.rep.error(codes.E252, f"a probability threshold must lie in [0, 1], not {v}",
                           t.value.span, hint="a probability is compared with a number "
                           "from 0 to 1, e.g. P>=0.65 [ ... ]")
            return None
        exact = t.value.text if isinstance(t.value, ast.Num) else repr(float(v))
        return ir.Threshold(t.op, float(v), exact)

    def _reward_property(self, d: ast.PropertyDecl, q: ast.RQuery) -> ir.Property:
        reward = self._reward_name(q)
        rp = q.path
        path: ir.RewardPath
        if isinstance(rp, ast.ReachReward):
            path = ir.RewardPath("F", self._bool(rp.target, _PROPERTY))
        elif isinstance(rp, ast.CumulativeReward):
            path = ir.RewardPath("C", bound=self._step_bound(rp.bound))
        else:
            path = ir.RewardPath("I", bound=self._step_bound(rp.at))
            rs = self.reward_structs.get(reward or "")
            if rs is not None and not any(it.action is None for it in rs.items):
                # Every Storm engine refuses it ("a reward model that does not define any
                # state-rewards"), and the whole Storm run with it.
                self.rep.error(
                    codes.E247, f"R{{\"{rs.name}\"}}[I=k] is always 0: \"{rs.name}\" has no "
                    "state rewards, and an instantaneous reward counts only those", q.span,
                    hint=f"Storm refuses it; add a state reward ('condition : value;') to "
                    f"\"{rs.name}\", or ask R{{\"{rs.name}\"}}=? [ C<=k ] for the action "
                    "rewards of the first k steps",
                    related=[Related(f"reward structure \"{rs.name}\"", rs.span)])
        return ir.Property(d.name.text, "R", q.opt, path, reward, d.span, *_written(q),
                           threshold=self._threshold(q, q.opt))

    def _reward_name(self, q: ast.RQuery) -> str | None:
        """The reward structure `R{"name"}` names; without a name, the only one there is."""
        if q.reward is None:
            if len(self.reward_names) != 1:
                self.rep.error(codes.E242, "name the reward structure: R{\"name\"}=? [...]", q.span,
                               hint=("reward structures: " + ", ".join(self.reward_names))
                               if self.reward_names else "declare one with 'rewards NAME { ... }'")
            return next(iter(self.reward_names), None)
        if q.reward not in self.reward_names:
            self.rep.error(codes.E203, f"reward structure \"{q.reward}\" is not declared",
                           q.reward_span or q.span, hint=did_you_mean(q.reward, self.reward_names))
        return q.reward

    def _step_bound(self, b: ast.Expr | None) -> E.Expr | None:
        """`F<=k`, `C<=k`, `I=k`: a constant int >= 0."""
        if b is None:
            return None
        x = self._expr(b, Ctx("a step bound", state=False))
        if x.type is not Type.INT:
            self.rep.error(codes.E241, "a step bound must be an int", b.span)
            return x
        try:
            k = scalar(x, self._const_env())
        except (EvalError, ArithmeticError):
            return x  # reported where it is computed (E245)
        if isinstance(k, int) and k < 0:
            self.rep.error(codes.E241, f"a step bound must be an int >= 0, not {k}", b.span,
                           hint="it counts steps; Storm refuses a negative one")
        return x


def _written(q: ast.PQuery | ast.RQuery) -> tuple[str, tuple[int, int] | None]:
    """The query's text as written and where its step bound stands (ir.Property.text)."""
    text = q.span.source.text
    p = q.path
    if isinstance(p, ast.Next | ast.ReachReward):
        return flat_text(text, q.span.start, q.span.end)
    if isinstance(p, ast.Until):
        op = next((i for i, j in tokens(text, p.left.span.end, p.right.span.start)
                   if text[i:j] == "U"), None)
        after = p.right.span.start
    else:  # F, G, C, I: the path starts at its letter
        op = p.span.start
        after = p.target.span.start if isinstance(p, ast.Eventually | ast.Globally) \
            else q.span.end - 1  # the closing ']'
    if op is None:
        return flat_text(text, q.span.start, q.span.end)
    site_end = max((j for _, j in tokens(text, op + 1, after)), default=op + 1)
    return flat_text(text, q.span.start, q.span.end, (op + 1, site_end))
