"""Fuzz inputs for afsmc, drawn from a `random.Random` so that the CI test (through
hypothesis's `st.randoms()`, which shrinks) and the long run in benchmarks/fuzz.py (a
seeded Random) draw from the same generators:

- `from_grammar`: a random walk of the lark grammar (grammar/afsm.lark), mostly
  well-formed files whose names rarely agree (the parser and the name errors);
- `spec`: a hand-written generator of whole machines whose names do agree (constants,
  variables, modes, actions, hazards, labels, rewards, properties over them), so the checks,
  the lowering and the backends run too;
- `mutate`: byte and token mutations of a seed file (the examples, the golden cases and the
  corpus).

Out of scope here, owned elsewhere: integer literals of more than 4,300 digits and inputs
large or deep enough to show superlinear time. `excluded` tells such inputs apart; the
generators stay far below both (literals under 40 digits, inputs under 64 KB), but
mutations of the golden case of 5,050 nested minus signs reach the deep ones.
"""

from __future__ import annotations

import random
import re
from functools import cache
from pathlib import Path

import lark
from lark.grammar import NonTerminal, Rule, Terminal

ROOT = Path(__file__).resolve().parents[2]
CORPUS = Path(__file__).resolve().parent / "corpus"

MAX_BYTES = 64 * 1024  # larger inputs belong to the linear-time work (issue 36, class 2)
MAX_DIGITS = 4000  # longer literals hit Python's int-string limit (issue 36, class 1)
MAX_NAME = 1000  # long identifiers: class 2 as well
# Long expressions: the resolver folds every constant level of a chain anew (`- - - K`,
# 4,000 levels: 12 s); class 2 too.
MAX_OPERATORS = 1000

NAMES = ["a", "b", "x", "y", "t", "Idle", "Run", "Go", "Done", "p", "w", "succ", "mode_x",
         "T", "N", "pos", "Move", "F", "G", "U", "X", "C", "I", "R", "P", "min", "max", "pow",
         "mod", "floor", "ceil", "init", "true_", "_", "__x", "e", "E", "inf", "nan", "s2"]
NUMBERS = ["0", "1", "2", "3", "10", "0.5", "0.1", "1.0", "1e3", "2e-3", "0.0", "100",
           "9223372036854775807", "9223372036854775808", "4611686018427387904",
           "281474976710656", "1e308", "1e309", "4.9e-324", "00", "007", "1.5e+2", "65536",
           "340282366920938463463374607431768211456", "0.30000000000000004", "999999999999"]
STRINGS = ['"a"', '"succ"', '"done"', '""', '"x y"', '"\\""', '"Run"']
COMMENTS = ["// c\n", "/* c */", "/**/", "/* a\n b */", "//\n"]


def excluded(data: bytes) -> str | None:
    """Why `data` is in a class fixed elsewhere (and so not judged here), or None."""
    if len(data) > MAX_BYTES:
        return f"larger than {MAX_BYTES} bytes"
    if re.search(rb"\d{%d}" % (MAX_DIGITS + 1), data):
        return f"a digit run longer than {MAX_DIGITS}"
    if re.search(rb"[A-Za-z0-9_]{%d}" % (MAX_NAME + 1), data):
        return f"a word longer than {MAX_NAME} characters"
    if max((sum(map(statement.count, (b"-", b"+", b"*", b"/", b"!", b"("))) for statement
            in data.split(b";")), default=0) > MAX_OPERATORS:
        return f"a statement with more than {MAX_OPERATORS} operators"
    return None


# ---- the grammar -------------------------------------------------------------------

@cache
def _grammar() -> tuple[dict[str, list[Rule]], dict[str, str], dict[str, int]]:
    """The rules by name, the literal text of each fixed terminal, and each rule's
    shortest derivation depth (to end a walk that grows too deep)."""
    from afsmc.syntax.grammar import grammar_text

    g = lark.Lark(grammar_text(), start="start", keep_all_tokens=True)
    rules: dict[str, list[Rule]] = {}
    for r in g.rules:
        rules.setdefault(r.origin.name, []).append(r)
    literals = {t.name: t.pattern.value for t in g.terminals
                if isinstance(t.pattern, lark.lexer.PatternStr)}
    depth = {name: 10**9 for name in rules}
    changed = True
    while changed:
        changed = False
        for name, alts in rules.items():
            for r in alts:
                d = _cost(r) + max((depth.get(s.name, 0) for s in r.expansion
                                    if isinstance(s, NonTerminal)), default=0)
                if d < depth[name]:
                    depth[name] = d
                    changed = True
    return rules, literals, depth


def _cost(rule: Rule) -> int:
    """A level of nesting: a rule that only hands on to another (`?sum: product`, the
    chain of precedence levels) adds none."""
    return 1 if len(rule.expansion) > 1 else 0


def _terminal(rng: random.Random, name: str, literals: dict[str, str],
              names: list[str]) -> str:
    if name in literals:
        return literals[name]
    if name == "NAME":
        return rng.choice(names)
    if name == "NUMBER":
        return rng.choice(NUMBERS)
    if name == "ESCAPED_STRING":
        return rng.choice(STRINGS)
    if name == "COMMENT":
        return rng.choice(COMMENTS)
    return " "


def from_grammar(rng: random.Random, max_depth: int = 8, max_tokens: int = 300,
                 start: str = "start", names: list[str] | None = None) -> str:
    """A file derived from the grammar's rule `start`, with names from `names`; past
    `max_depth` every choice takes the shortest way out."""
    rules, literals, depth = _grammar()
    out: list[str] = []

    def walk(name: str, level: int) -> None:
        alts = rules[name]
        if level >= max_depth or len(out) > max_tokens:
            best = min(depth_of(r) for r in alts)
            alts = [r for r in alts if depth_of(r) == best]
        rule = rng.choice(alts)
        for sym in rule.expansion:
            if isinstance(sym, Terminal):
                out.append(_terminal(rng, sym.name, literals, names or NAMES))
                if rng.random() < 0.03:
                    out.append(rng.choice(COMMENTS))
            else:
                walk(sym.name, level + _cost(rule))

    def depth_of(r: Rule) -> int:
        return _cost(r) + max((depth[s.name] for s in r.expansion
                               if isinstance(s, NonTerminal)), default=0)

    walk(start, 0)
    return "".join(t + rng.choice(" \n") if rng.random() < 0.1 else t + " " for t in out)


def with_declaration(rng: random.Random, data: bytes) -> bytes:
    """`data` with one declaration drawn from the grammar put in at a line break, with the
    names the file already uses (and a few others), so that it is checked with the rest."""
    words = sorted({w.decode() for w in re.findall(rb"\b[A-Za-z_]\w*\b", data)})
    names = [*words, *words, "x", "Zed"] if words else NAMES
    decl = from_grammar(rng, max_depth=rng.randint(2, 6), start=rng.choice(_DECLS),
                        names=names).encode()
    lines = data.split(b"\n")
    at = rng.randint(0, len(lines))
    return b"\n".join([*lines[:at], decl, *lines[at:]])


_DECLS = ["const_decl", "param_decl", "var_decl", "mode_decl", "action_decl", "hazard_decl",
          "formula_decl", "label_decl", "rewards_decl", "property_decl", "action_decl",
          "property_decl", "var_decl"]


# ---- whole machines ----------------------------------------------------------------

class _Spec:
    """The names a generated machine declares, for expressions that use them."""

    def __init__(self, rng: random.Random) -> None:
        self.rng = rng
        self.ints: list[str] = []
        self.doubles: list[str] = []
        self.bools: list[str] = []
        self.modes: list[str] = []
        self.actions: list[str] = []
        self.labels: list[str] = []
        self.rewards: list[str] = []
        self.intervals: list[str] = []  # interval constants: only in updates
        self.working: list[str] = []  # the modes that are not final

    def num(self) -> str:
        """Mostly a small integer; now and then a fraction or an edge case."""
        r = self.rng.random()
        if r < 0.97:
            return str(self.rng.choice([0, 1, 2, 3, 5, 10]))
        if r < 0.99:
            return self.rng.choice(["0.5", "0.25", "0.9", "0.1", "1.0", "0.0"])
        return self.rng.choice(NUMBERS)

    def int_expr(self, depth: int = 0) -> str:
        rng = self.rng
        r = rng.random()
        if depth > 3 or r < 0.35:
            pool = [*self.ints, self.num()]
            return rng.choice(pool)
        if r < 0.75:
            op = rng.choice(["+", "-", "*", "+", "-", "+"] if rng.random() < 0.95 else ["/"] if rng.random() < 0.6 else ["*"])
            return f"{self.int_expr(depth + 1)} {op} {self.int_expr(depth + 1)}"
        if r < 0.82:
            return f"-{self.int_expr(depth + 1)}"
        if r < 0.88:
            return f"({self.int_expr(depth + 1)})"
        if r < 0.94:
            f = rng.choice(["min", "max", "pow", "mod", "floor", "ceil"])
            n = 1 if f in ("floor", "ceil") else 2
            return f"{f}({', '.join(self.int_expr(depth + 1) for _ in range(n))})"
        return f"({self.bool_expr(depth + 1)} ? {self.int_expr(depth + 1)} : " \
               f"{self.int_expr(depth + 1)})"

    def bool_expr(self, depth: int = 0) -> str:
        rng = self.rng
        r = rng.random()
        if depth > 3 or r < 0.2:
            return rng.choice([*self.bools, "true", "false"])
        if r < 0.55:
            op = rng.choice(["<", "<=", ">", ">=", "==", "!="])
            return f"{self.int_expr(depth + 1)} {op} {self.int_expr(depth + 1)}"
        if r < 0.7:
            op = rng.choice(["&&", "||", "=>"])
            return f"{self.bool_expr(depth + 1)} {op} {self.bool_expr(depth + 1)}"
        if r < 0.78:
            return f"!{self.bool_expr(depth + 1)}"
        if r < 0.88 and self.modes:
            return rng.choice([f"mode == {rng.choice(self.modes)}",
                               f"mode in {self.mode_set()}"])
        if r < 0.94 and self.labels:
            return f'"{rng.choice(self.labels)}"'
        return f"({self.bool_expr(depth + 1)})"

    def prob_expr(self) -> str:
        rng = self.rng
        r = rng.random()
        if r < 0.5:
            return rng.choice([*self.doubles, "0.5", "0.1", "0.9", "1", "0"])
        if r < 0.75 and self.doubles:
            return f"1 - {rng.choice(self.doubles)}"
        if r < 0.8 and self.actions and rng.random() < 0.1:
            return f"w({rng.choice(self.actions)})"
        return f"{self.int_expr(2)} / {rng.choice(['10', '100', '2', '0', '10', '100'])}"

    def weight(self) -> str:
        if self.actions and self.rng.random() < 0.3:
            return f"1 - w({self.rng.choice(self.actions)})"
        return self.rng.choice([self.prob_expr(), self.int_expr(1)])

    def mode_set(self) -> str:
        rng = self.rng
        r = rng.random()
        modes = self.working if self.working and rng.random() < 0.95 else self.modes
        if r < 0.5 or not modes:
            return rng.choice(modes or ["Idle"])
        if r < 0.7:
            return "*"
        picked = rng.sample(modes, rng.randint(1, len(modes)))
        if r < 0.8:
            return "* except {" + ", ".join(picked) + "}"
        items = [*picked, *(str(rng.randint(0, len(self.modes))) for _ in range(rng.random() < 0.2))]
        if rng.random() < 0.1:
            items.append(f"{rng.randint(0, 2)}..{rng.randint(0, len(self.modes))}")
        return "{" + ", ".join(items) + "}"

    def update(self, variables: list[tuple[str, bool]]) -> str:
        """Mostly each variable once and one goto at most, as the checks want."""
        rng = self.rng
        parts = []
        seen: set[str] = set()
        for _ in range(rng.randint(1, 3)):
            r = rng.random()
            if r < 0.3 and self.modes and ("goto" not in seen or rng.random() < 0.01):
                parts.append(f"goto {rng.choice(self.modes)}")
                seen.add("goto")
            elif variables:
                name, is_bool = rng.choice(variables)
                if name in seen and rng.random() < 0.99:
                    continue
                seen.add(name)
                if is_bool:
                    parts.append(f"{name} := {self.bool_expr(2)}")
                else:
                    op = rng.choice([":=", "+=", "-="])
                    value = self.int_expr(2)
                    if self.intervals and rng.random() < 0.3:
                        value = rng.choice(self.intervals)
                    parts.append(f"{name} {op} {value}")
        return ", ".join(parts) or "skip"


def spec(rng: random.Random) -> str:
    """A whole machine whose declarations refer to each other."""
    s = _Spec(rng)
    lines = [f"machine {rng.choice(['m', 'patrol', 'x'])};"]
    for i in range(rng.randint(0, 4)):
        name = f"K{i}"
        kind = rng.choice(["int", "int", "double", "prob", "bool"])
        keyword = rng.choice(["const", "const", "param"])
        if kind == "bool":
            value = s.bool_expr(3)
        elif kind == "int":
            value = s.int_expr(2)
            if keyword == "const" and rng.random() < 0.2:
                value = f"[{s.int_expr(3)}, {s.int_expr(3)}]"
        elif rng.random() < 0.8:
            value = rng.choice(["0.1", "0.5", "0.01", "0.9", "1", "0", s.prob_expr()])
        else:
            value = f"[{s.num()}, {s.num()}]"
            kind = "int" if rng.random() < 0.9 else kind
        lines.append(f"{keyword} {kind} {name} = {value};")
        if value.startswith("[") and kind == "int" and rng.random() < 0.95:
            s.intervals.append(name)
        else:
            {"int": s.ints, "bool": s.bools}.get(kind, s.doubles).append(name)
    variables: list[tuple[str, bool]] = []
    for i in range(rng.randint(1, 3)):
        name = f"v{i}"
        if rng.random() < 0.2:
            lines.append(f"var {name} : bool init {rng.choice(['true', 'false'])};")
            s.bools.append(name)
            variables.append((name, True))
            continue
        hi = rng.choice(["3", "5", "10", "1", "2", "4", s.int_expr(3)])
        lo = rng.choice(["0", "0", "1", "-2"])
        init = rng.choice([lo, lo, lo, "1", hi, s.int_expr(3)])
        clamp = " clamp" if rng.random() < 0.3 else ""
        lines.append(f"var {name} : [{lo}..{hi}] "
                     f"init {init}{clamp};")
        s.ints.append(name)
        variables.append((name, False))
    modes = rng.sample(["Idle", "Run", "Go", "Done", "Fail", "Dock"], rng.randint(1, 5))
    finals = ""
    for i, m in enumerate(modes):
        number = f" = {i if rng.random() < 0.9 else rng.randint(0, 9)}" \
            if rng.random() < 0.6 else ""
        attrs = " initial" if i == 0 else ""
        if i == len(modes) - 1 and i and rng.random() < 0.7:
            attrs += " final"
            finals += f"mode {m} "
        lines.append(f"mode {m}{number}{attrs};")
    s.modes = modes
    s.working = [m for m in modes if f"mode {m} " not in finals]
    for i in range(rng.randint(0, 2)):
        lines.append(f"formula f{i} = {s.int_expr(2) if rng.random() < 0.5 else s.bool_expr(2)};")
    for i in range(rng.randint(1, 5)):
        name = f"A{i}"
        guard = f" when {s.bool_expr(1)}" if rng.random() < 0.6 else ""
        weight = f" weight {s.weight()}" if rng.random() < 0.5 else ""
        if rng.random() < 0.5:
            body = f"    {s.update(variables)};"
        else:
            body = "\n".join(f"    {s.prob_expr()}: {s.update(variables)};"
                             for _ in range(rng.randint(1, 3)))
        lines.append(f"action {name} in {s.mode_set()}{guard}{weight} {{\n{body}\n}}")
        s.actions.append(name)
    for i in range(rng.randint(0, 2)):
        trigger = f"with probability {s.prob_expr()}" if rng.random() < 0.6 \
            else f"when {s.bool_expr(1)}"
        lines.append(f"hazard H{i} from {s.mode_set()} {trigger} {{ {s.update(variables)}; }}")
    for i in range(rng.randint(0, 2)):
        lines.append(f"label l{i} = {s.bool_expr(1)};")
        s.labels.append(f"l{i}")
    for i in range(rng.randint(0, 2)):
        item = f"[{rng.choice(s.actions)}] {s.bool_expr(2)} : {s.int_expr(2)};" \
            if rng.random() < 0.4 else f"{s.bool_expr(2)} : {s.int_expr(2)};"
        lines.append(f"rewards r{i} {{ {item} }}")
        s.rewards.append(f"r{i}")
    for i in range(rng.randint(0, 3)):
        lines.append(f"property q{i} = {_query(s)};")
    return "\n".join(lines) + "\n"


def _query(s: _Spec) -> str:
    rng = s.rng
    bound = rng.choice(["", "", f"<={rng.choice(['0', '5', '20', 'K0', '(K0 + 1)'])}"])
    if s.rewards and rng.random() < 0.3:
        r = rng.choice(s.rewards)
        path = rng.choice([f"F {s.bool_expr(2)}", f"C{bound}", "C",
                           f"I={rng.choice(['3', '0', 'K0'])}"])
        return f'R{{"{r}"}}{rng.choice(["", "min", "max"])}=? [ {path} ]'
    op = rng.choice(["P", "Pmin", "Pmax"])
    path = rng.choice([f"F{bound} {s.bool_expr(1)}", f"G{bound} {s.bool_expr(1)}",
                       f"{s.bool_expr(2)} U{bound} {s.bool_expr(2)}", f"X {s.bool_expr(2)}"])
    return f"{op}=? [ {path} ]"


# ---- mutations ---------------------------------------------------------------------

TOKENS = [b"mode", b"goto", b"weight", b"when", b"w(A0)", b"[0..2]", b"1e309", b"0.0", b"/ 0",
          b"init", b"clamp", b"final", b"initial", b"{", b"}", b"(", b")", b";", b",", b":",
          b"=?", b"[", b"]", b"..", b"P=? [ F true ]", b"hazard", b"action", b"*", b"except",
          b"\xc3\xa9", b"\xff", b"\x00", b"\t", b"\r\n", b"\r", b"\n", b"\xef\xbb\xbf", b"//",
          b"/*", b"*/", b'"', b"-", b"--", b"9223372036854775807", b"-9223372036854775808",
          b"2147483648", b"1e-400", b"pow(2, 63)", b"mod(", b"min(", b"true", b"false",
          b"from sim uav.transport", b"param", b"const", b"var", b"formula", b"label",
          b"rewards", b"property", b"R{\"r\"}=? [ C ]", b"mode in {", b"\xe2\x80\x8b"]


def seeds() -> list[bytes]:
    """The seed files: the examples, the golden cases' inputs, the corpus."""
    paths = [*sorted((ROOT / "examples").glob("*.afsm")),
             *sorted((ROOT / "tests" / "golden" / "cases").glob("*/input.afsm")),
             *sorted(CORPUS.glob("*.afsm"))]
    return [p.read_bytes() for p in paths]


def mutate(rng: random.Random, data: bytes) -> bytes:
    """1 to 6 mutations (mostly one or two, so that many files still parse): delete or
    duplicate a span, set a byte, insert a token, swap two tokens of the file, or put
    another number or name in place of one."""
    for _ in range(rng.choice([1, 1, 1, 2, 2, 3, 4, 6])):
        n = len(data)
        i = rng.randint(0, n)
        j = min(n, i + rng.choice([1, 1, 2, 4, 8, 40, 200]))
        op = rng.random()
        if op < 0.2:
            data = data[:i] + data[j:]
        elif op < 0.3:
            data = data[:j] + data[i:j] + data[j:]
        elif op < 0.33 and n:
            k = rng.randint(0, n - 1)
            data = data[:k] + bytes([rng.randint(0, 255)]) + data[k + 1:]
        elif op < 0.6:
            data = data[:i] + rng.choice(TOKENS) + data[i:]
        elif op < 0.75:
            words = re.split(rb"(\W)", data)
            if len(words) > 2:
                a, b = rng.randrange(len(words)), rng.randrange(len(words))
                words[a], words[b] = words[b], words[a]
                data = b"".join(words)
        else:
            # a number or a name replaced by another of its kind
            found = list(re.finditer(rb"\b\d+(\.\d+)?\b|\b[A-Za-z_]\w*\b", data))
            if found:
                m = rng.choice(found)
                new = rng.choice(NUMBERS if m.group()[:1].isdigit() else NAMES).encode()
                data = data[:m.start()] + new + data[m.end():]
    return data


def splice(rng: random.Random, a: bytes, b: bytes) -> bytes:
    """The start of one file and the end of another, cut at line breaks."""
    la, lb = a.split(b"\n"), b.split(b"\n")
    return b"\n".join(la[:rng.randint(0, len(la))] + lb[rng.randint(0, len(lb)):])
