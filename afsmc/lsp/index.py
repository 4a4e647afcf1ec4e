"""What the language server knows about one document, computed from the compiler's own AST
and IR: where every name is declared and used, and what to say about it on hover.

Independent of LSP types (offsets, not line/character), so it is tested directly too.
"""

from __future__ import annotations

import dataclasses
import re
from bisect import bisect_right
from dataclasses import dataclass, field
from typing import Any

from afsmc.diagnostics import CompileError, Source, Span
from afsmc.model import ir
from afsmc.model.expr import Type
from afsmc.model.pretty import number, with_names
from afsmc.syntax import ast
from afsmc.syntax.parser import parse

# Namespaces, as the resolver keeps them: constants, variables, modes and formulas share one.
VALUE, ACTION, LABEL, REWARD, PROPERTY, FIELD = "value", "action", "label", "reward", \
    "property", "field"

NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")

KEYWORDS = (
    "machine", "const", "param", "int", "double", "prob", "bool", "var", "init", "clamp", "mode",
    "initial", "final", "action", "in", "when", "weight", "goto", "skip", "hazard", "from",
    "with", "probability", "sim", "formula", "label", "rewards", "property", "except", "true",
    "false", "P", "Pmin", "Pmax", "R", "min", "max", "F", "G", "U", "X", "C", "I",
)


@dataclass(frozen=True)
class Occurrence:
    ns: str
    name: str
    start: int
    end: int
    is_def: bool


@dataclass
class Definition:
    ns: str
    name: str
    kind: str  # constant, variable, mode, formula, action, hazard, label, rewards, property, field
    ident: Span
    decl: Any  # the AST declaration


@dataclass
class Index:
    text: str
    module: ast.Module
    defs: dict[tuple[str, str], Definition] = field(default_factory=dict)
    occurrences: list[Occurrence] = field(default_factory=list)

    def at(self, offset: int) -> Occurrence | None:
        """The name at `offset` (a cursor just after a name is still on it)."""
        starts = [o.start for o in self.occurrences]
        i = bisect_right(starts, offset) - 1
        for o in self.occurrences[max(0, i - 1): i + 1]:
            if o.start <= offset <= o.end:
                return o
        return None

    def definition(self, occ: Occurrence) -> Definition | None:
        return self.defs.get((occ.ns, occ.name))

    def references(self, ns: str, name: str, include_def: bool = True) -> list[Occurrence]:
        return [o for o in self.occurrences
                if o.ns == ns and o.name == name and (include_def or not o.is_def)]

    def names(self, ns: str, kinds: tuple[str, ...] = ()) -> list[Definition]:
        return sorted((d for d in self.defs.values() if d.ns == ns and (not kinds or d.kind in kinds)),
                      key=lambda d: d.ident.start)


def build(module: ast.Module, text: str) -> Index:
    idx = Index(text, module)
    occ: list[Occurrence] = []

    def define(ns: str, ident: ast.Ident, kind: str, decl: Any) -> None:
        idx.defs.setdefault((ns, ident.text), Definition(ns, ident.text, kind, ident.span, decl))
        occ.append(Occurrence(ns, ident.text, ident.span.start, ident.span.end, True))

    def use(ns: str, name: str, span: Span, start: int | None = None, end: int | None = None) -> None:
        occ.append(Occurrence(ns, name, span.start if start is None else start,
                              span.end if end is None else end, False))

    def walk(node: Any) -> None:
        if isinstance(node, ast.Name):
            use(VALUE, node.name.text, node.name.span)
        elif isinstance(node, ast.Call):
            if node.func.text == "w" and len(node.args) == 1 and isinstance(node.args[0], ast.Name):
                use(ACTION, node.args[0].name.text, node.args[0].name.span)
            else:
                walk(node.args)
        elif isinstance(node, ast.FieldRef):
            use(VALUE, node.base.text, node.base.span)
            use(FIELD, f"{node.base.text}.{node.field.text}", node.field.span)
        elif isinstance(node, ast.LValue):
            use(VALUE, node.name.text, node.name.span)
            if node.field is not None:
                use(FIELD, f"{node.name.text}.{node.field.text}", node.field.span)
        elif isinstance(node, ast.LabelRef):  # inside the quotes
            use(LABEL, node.name, node.span, node.span.start + 1, node.span.end - 1)
        elif isinstance(node, ast.ModeName):
            use(VALUE, node.name.text, node.name.span)
        elif isinstance(node, ast.Goto):
            use(VALUE, node.mode.text, node.mode.span)
        elif isinstance(node, ast.RewardItem):
            if node.action is not None:
                use(ACTION, node.action.text, node.action.span)
            walk(node.guard)
            walk(node.value)
        elif isinstance(node, ast.RQuery):
            if node.reward is not None and node.reward_span is not None:
                s = node.reward_span
                use(REWARD, node.reward, s, s.start + 1, s.end - 1)
            walk(node.path)
            walk(node.threshold)  # a requirement's constants: R{"r"}<=(LIMIT) [ ... ]
        elif isinstance(node, tuple):
            for x in node:
                walk(x)
        elif dataclasses.is_dataclass(node) and not isinstance(node, (type, ast.Ident, Span)):
            for f in dataclasses.fields(node):
                walk(getattr(node, f.name))

    decls = list(module.decls)
    while decls:
        d = decls.pop(0)
        if isinstance(d, ast.AgentDecl):  # an agent's declarations, as if they stood here
            decls[:0] = d.decls
            if d.clock is not None:
                use(VALUE, d.clock.text, d.clock.span)
        elif isinstance(d, ast.AgentsDecl):  # the instances' arguments (`r1 = Robot(B_FULL)`)
            walk(tuple(a for i in d.instances for a in i.args))
        elif isinstance(d, (ast.ConstDecl, ast.ParamDecl)):
            define(VALUE, d.name, "constant", d)
            walk(d.value if isinstance(d, ast.ConstDecl) else d.default)
        elif isinstance(d, ast.VarDecl):
            define(VALUE, d.name, "variable", d)
            if isinstance(d.type, ast.TupleType):
                for f in d.type.fields:
                    idx.defs.setdefault((FIELD, f"{d.name.text}.{f.name.text}"), Definition(
                        FIELD, f"{d.name.text}.{f.name.text}", "field", f.name.span, d))
                    occ.append(Occurrence(FIELD, f"{d.name.text}.{f.name.text}", f.name.span.start,
                                          f.name.span.end, True))
                    walk(f.type)
            else:
                walk(d.type)
            walk(d.init)
        elif isinstance(d, ast.ModeDecl):
            define(VALUE, d.name, "mode", d)
        elif isinstance(d, ast.FormulaDecl):
            define(VALUE, d.name, "formula", d)
            walk(d.value)
        elif isinstance(d, (ast.ActionDecl, ast.HazardDecl)):
            define(ACTION, d.name, "action" if isinstance(d, ast.ActionDecl) else "hazard", d)
            walk(d.modes)
            walk(d.guard if isinstance(d, ast.ActionDecl) else d.trigger)
            walk(d.weight)
            walk(d.body)
        elif isinstance(d, ast.LabelDecl):
            define(LABEL, d.name, "label", d)
            walk(d.value)
        elif isinstance(d, ast.RewardsDecl):
            define(REWARD, d.name, "rewards", d)
            walk(d.items)
        elif isinstance(d, ast.PropertyDecl):
            define(PROPERTY, d.name, "property", d)
            walk(d.query)
    idx.occurrences = sorted(occ, key=lambda o: (o.start, o.end))
    return idx


# ---- a document that has never parsed --------------------------------------------------

# The start of a line that starts a declaration (`mode X`, not `mode == X` or `mode in`).
_DECL_START = re.compile(r"^[ \t]*(?:(?:machine|const|param|var|action|hazard|formula|label|"
                         r"rewards|property)\b|mode[ \t]+(?!in\b)[A-Za-z_])", re.M)
_COMMENT = re.compile(r"//[^\n]*|/\*[\s\S]*?(?:\*/|\Z)")
_NAME = r"([A-Za-z_][A-Za-z0-9_]*)"
_TYPE = r"(?:int|double|prob|bool)"
_SCAN = (  # (pattern, namespace, kind) of the declarations a lexical scan finds
    (re.compile(rf"\bmode[ \t]+(?!in\b){_NAME}"), VALUE, "mode"),
    (re.compile(rf"\b(?:const|param)\s+{_TYPE}\s+{_NAME}"), VALUE, "constant"),
    (re.compile(rf"\bvar\s+{_NAME}"), VALUE, "variable"),
    (re.compile(rf"\bformula\s+{_NAME}"), VALUE, "formula"),
    (re.compile(rf"\baction\s+{_NAME}"), ACTION, "action"),
    (re.compile(rf"\bhazard\s+{_NAME}"), ACTION, "hazard"),
    (re.compile(rf"\blabel\s+{_NAME}"), LABEL, "label"),
    (re.compile(rf"\brewards\s+{_NAME}"), REWARD, "rewards"),
    (re.compile(rf"\bproperty\s+{_NAME}"), PROPERTY, "property"),
)
_FIELDS = re.compile(rf"\bvar\s+{_NAME}\s*:\s*\(([^()]*)\)")
RECOVERY_PARSES = 8  # at most this many parses of a broken text (~30 ms each on uav.afsm)


def _blank(text: str, start: int, end: int) -> str:
    """`text` with [start, end) turned into spaces, line breaks kept (offsets stay valid)."""
    return text[:start] + re.sub(r"[^\n]", " ", text[start:end]) + text[end:]


def _declaration_at(text: str, offset: int) -> tuple[int, int]:
    """The lines of the declaration around `offset`: from the line that starts it to the
    line that starts the next one (by the look of the lines, as the text may not parse)."""
    starts = [m.start() for m in _DECL_START.finditer(text)]
    i = bisect_right(starts, offset) - 1
    start = starts[i] if i >= 0 else 0
    end = starts[i + 1] if i + 1 < len(starts) else len(text)
    return start, end


def recover(text: str, offset: int, path: str) -> Index:
    """Names for a text that does not parse (completion in a document that has never parsed):
    the text is parsed again with the broken part blanked out, first the line at `offset`
    (the one being typed), then the declaration around it, then each declaration a syntax
    error points into. The declarations found by a lexical scan (`mode NAME`, `action NAME`,
    `const int NAME`, ...) are added, and are all there is if no such text parses."""
    line = text.rfind("\n", 0, offset) + 1
    line_end = text.find("\n", offset)
    line_end = len(text) if line_end < 0 else line_end
    typing = _blank(text, line, line_end)
    found = None
    for cand in (typing, _blank(text, *_declaration_at(text, offset))):
        for _ in range(RECOVERY_PARSES // 2):
            try:
                found = build(parse(cand, path), cand)
                break
            except CompileError as exc:
                at = [d.span.start for d in exc.diagnostics if d.span is not None]
                if not at:
                    break
                start, end = _declaration_at(cand, at[0])
                if not cand[start:end].strip():
                    break  # nothing left to blank there
                cand = _blank(cand, start, end)
        if found is not None:
            break
    # What was blanked may declare names too (blanking goes by lines, and may take more than
    # the broken declaration): the scan adds them, but not a name on the line being typed.
    scanned = scan(typing, path)
    if found is None:
        return scanned
    for key, d in scanned.defs.items():
        found.defs.setdefault(key, d)
    return found


def scan(text: str, path: str = "<scan>") -> Index:
    """The declarations found by their look alone (no parse): names and kinds, enough to
    complete; `decl` is None."""
    code = _COMMENT.sub(lambda m: " " * len(m.group()), text)
    src = Source(path, text)
    idx = Index(text, ast.Module(None, (), Span.whole_file(src)))

    def define(ns: str, name: str, kind: str, start: int) -> None:
        if name not in KEYWORDS:
            idx.defs.setdefault((ns, name), Definition(
                ns, name, kind, Span.at_offset(src, start, start + len(name)), None))

    for pattern, ns, kind in _SCAN:
        for m in pattern.finditer(code):
            define(ns, m.group(1), kind, m.start(1))
    for m in _FIELDS.finditer(code):
        for f in re.finditer(rf"{_NAME}\s*:", m.group(2)):
            define(FIELD, f"{m.group(1)}.{f.group(1)}", "field", m.start(2) + f.start(1))
    return idx


# ---- hover ---------------------------------------------------------------------------


def declaration_text(d: Definition, text: str) -> str:
    """The declaration as written, up to its body: `action Search in Search when ...`."""
    decl = d.decl
    if d.kind == "field":
        f = next(f for f in decl.type.fields if f.name.span == d.ident)
        return f"var {decl.name.text} : (... {text[f.span.start:f.span.end]} ...)"
    end = decl.span.end
    if isinstance(decl, (ast.ActionDecl, ast.HazardDecl)):
        end = decl.body.span.start
    elif isinstance(decl, ast.RewardsDecl):
        end = text.find("{", decl.name.span.end)
    snippet = " ".join(text[decl.span.start:end].split())
    return snippet if len(snippet) <= 300 else snippet[:297] + "..."


def hover(d: Definition, text: str, model: ir.Model | None) -> str:
    """Markdown for a name: its declaration and what the compiler made of it."""
    lines = ["```afsm", declaration_text(d, text), "```"]
    facts = _facts(d, model) if model is not None else []
    lines.extend(f"- {f}" for f in facts)
    return "\n".join(lines)


def _facts(d: Definition, model: ir.Model) -> list[str]:
    show = with_names(model.display_names())
    try:
        if d.kind == "constant":
            c = model.constant(d.name)
            out = []
            if c.interval is not None and c.interval[0] != c.interval[1]:
                out.append(f"value: an interval, {c.interval[0]} to {c.interval[1]} "
                           "(the model checker takes both ends)")
            else:
                out.append(f"value: `{number(c.value)}` ({c.declared_type})")
            if c.is_param:
                out.append(f"open constant: `--const {c.name}=VALUE` overrides it")
            if c.source is not None:
                policy = ", ".join(f"{k} = {number(v)}" for k, v in c.source.policy)
                what = "simulation" if c.source.column is None else "data file"
                out.append(f"source: {what} `{c.source.display}`"
                           + (f" with {policy}" if policy else ""))
            return out
        if d.kind == "variable":
            out = []
            for v in model.variables:
                if v.name == d.name or v.display.startswith(d.name + "."):
                    kind = "bool" if v.type is Type.BOOL else f"[{v.lo}..{v.hi}]"
                    out.append(f"`{v.display}`: range {kind}, initially `{number(v.init)}`"
                               + (", clamped to its range" if v.clamp else ""))
            return out
        if d.kind == "field":
            return [f"range [{v.lo}..{v.hi}], initially `{number(v.init)}`"
                    for v in model.variables if v.display == d.name]
        if d.kind == "mode":
            m = model.mode(d.name)
            flags = [x for x, on in (("initial", m.initial), ("final", m.final)) if on]
            return [f"mode number {m.number}" + (f" ({', '.join(flags)})" if flags else "")]
        if d.kind in ("action", "hazard"):
            names = model.mode_names
            acts = [a for a in model.actions if a.name == d.name]
            if acts:
                a = acts[0]
                return [f"modes: {', '.join(names.get(n, str(n)) for n in a.modes)}",
                        f"guard: `{show(a.guard)}`", f"weight: `{show(a.weight)}`"] + (
                    ["a preemptive hazard: it fires before the mode's actions"]
                    if a.kind == "preemptive" else [])
            hz = [h for h in model.hazards if h.name == d.name]
            if hz:
                h = hz[0]
                return [f"modes: {', '.join(names.get(n, str(n)) for n in h.modes)}",
                        f"probability: `{show(h.prob)}`, woven into every action of these modes"]
            return []
        if d.kind == "formula":
            return [f"`{show(model.formula(d.name).value)}`"]
        if d.kind == "label":
            return [f"`{show(model.label(d.name).value)}`"]
    except StopIteration:  # the model is from an older version of the text
        return []
    return []
