"""Quick fixes: every diagnostic whose hint names an edit ("add ';' here", "did you mean
'level'?", "write 'final' once", "choose another name, e.g. 'x'", ...) offers it as a code
action with a WorkspaceEdit.

The fixes are worked out when the diagnostics are published, as edits on offsets of the text
they were computed for, and travel in the LSP diagnostic's `data`; a code action request
turns them into ranges of the editor's text, if that text is still the same.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from lsprotocol import types as T

from afsmc.diagnostics import Diagnostic
from afsmc.lsp import index as I
from afsmc.lsp.positions import current, to_range
from afsmc.lsp.state import AfsmServer, guarded

Edit = tuple[int, int, str]  # [start, end) of the text, replaced by the string


@dataclass(frozen=True)
class Fix:
    title: str
    edits: tuple[Edit, ...]

    def to_data(self) -> dict[str, Any]:
        return {"title": self.title, "edits": [list(e) for e in self.edits]}


_ADD = re.compile(r"add '([^']+)' here")
_MEAN = re.compile(r"did you mean '([^']+)'\?")
_INSTEAD = re.compile(r"write '([^']+)' instead of '([^']+)'")
_ONCE = re.compile(r"write '([^']+)' once")
_NAME = re.compile(r"(?:choose another name|rename the action), e\.g\. '([A-Za-z_]\w*)'")
_SPACE = re.compile(r"put a space after it: '([^']+)'")
_WRITE = re.compile(r"write '([^']+)'")
_TIE = re.compile(r"weights of (\w+) and (\w+) tie")
# codes whose "write '...'" hint is the whole flagged text, rewritten
_REWRITES = {"E213", "E121", "E119"}


def fixes(d: Diagnostic, text: str, index: I.Index | None) -> list[Fix]:
    """The edits `d`'s hint names, on `text` (the text `d` was found in)."""
    if d.span is None:
        return []
    start, end = d.span.start, d.span.end
    hint = d.hint or ""
    out: list[Fix] = []
    if m := _ADD.search(hint):
        out.append(Fix(f"Add '{m[1]}'", ((start, start, m[1]),)))
    if m := _MEAN.search(hint):
        out.append(Fix(f"Change to '{m[1]}'", ((start, end, m[1]),)))
    if (m := _INSTEAD.search(hint)) and text[start:end] == m[2]:
        out.append(Fix(f"Write '{m[1]}'", ((start, end, m[1]),)))
    if (m := _ONCE.search(hint)) and text[start:end] == m[1]:
        gap = start
        while gap > 0 and text[gap - 1] in " \t":
            gap -= 1
        out.append(Fix(f"Remove the second '{m[1]}'", ((gap, end, ""),)))
    if m := _SPACE.search(hint):
        out.append(Fix(f"Write '{m[1]}'", ((start, end, m[1]),)))
    if (m := _WRITE.search(hint)) and d.code in _REWRITES:
        out.append(Fix(f"Write '{m[1]}'", ((start, end, m[1]),)))
    if (m := _NAME.search(hint)) and index is not None:
        out += _rename(index, start, end, m[1])
    if "mark it final" in hint and (semi := text.find(";", start)) >= 0:
        out.append(Fix("Mark the mode final", ((semi, semi, " final"),)))
    if "make the last outcome '1 - ...'" in hint:
        out += _complement(text, start, end)
    out += _rewrites(d, text, start, end)
    if d.code == "E301" and (m := _TIE.search(d.message)) and d.related:
        other = d.related[0].span
        out.append(Fix(f"Give {m[2]} the weight 1 - w({m[1]})",
                       ((other.start, other.end, f"1 - w({m[1]})"),)))
    return out


def _rename(index: I.Index, start: int, end: int, new: str) -> list[Fix]:
    occ = index.at(start)
    if occ is None and index.text[max(0, start - 8):start].rstrip() == "machine":
        # the machine's name is named nowhere else
        return [Fix(f"Rename the machine to '{new}'", ((start, end, new),))]
    if occ is None or (occ.start, occ.end) != (start, end) or (occ.ns, new) in index.defs:
        return []
    edits = tuple((o.start, o.end, new) for o in index.references(occ.ns, occ.name))
    return [Fix(f"Rename '{occ.name}' to '{new}'", edits)]


_OUTCOME = re.compile(r"(?P<prob>[^;:{}]+?)\s*:(?!=)")


def _complement(text: str, start: int, end: int) -> list[Fix]:
    """The last outcome's probability becomes 1 minus the others'."""
    body = text[start:end]
    probs = [(start + m.start("prob") + len(m["prob"]) - len(m["prob"].lstrip()),
              start + m.end("prob"), m["prob"].strip())
             for m in _OUTCOME.finditer(body) if m.start() == 0 or body[m.start() - 1] in ";\n \t"]
    probs = [p for p in probs if p[2]]
    if len(probs) < 2:
        return []
    others = " + ".join(p[2] if re.fullmatch(r"[\w.]+", p[2]) else f"({p[2]})"
                        for p in probs[:-1])
    rest = f"1 - {others}" if len(probs) == 2 else f"1 - ({others})"
    last = probs[-1]
    return [Fix(f"Make the last outcome '{rest}'", ((last[0], last[1], rest),))]


@guarded
def code_action(ls: AfsmServer, params: T.CodeActionParams) -> list[T.CodeAction]:
    uri = params.text_document.uri
    doc = current(ls, uri)
    st = ls.docs.get(uri)
    if st is None or st.published != doc.source:
        return []  # the offsets are those of another text
    out = []
    for diag in params.context.diagnostics:
        if not isinstance(diag.data, list):
            continue
        for fix in diag.data:
            edits = [T.TextEdit(range=to_range(doc, a, b), new_text=s) for a, b, s in fix["edits"]]
            out.append(T.CodeAction(
                title=fix["title"], kind=T.CodeActionKind.QuickFix, diagnostics=[diag],
                edit=T.WorkspaceEdit(changes={uri: edits}), is_preferred=len(diag.data) == 1))
    return out


_OPERATOR = re.compile(r"is not (?:an operator in afsm|a comparison)[:;] write '([^']+)'")
_CLAMP = re.compile(r"declare (?:the tuple )?'(\w+)' with 'clamp'")
_MOD = re.compile(r"write 'mod\(([^,']+), ([^']+)\)'")
_IF = re.compile(r"write '(\w+) := (\(.+\))'$")


def _rewrites(d: Diagnostic, text: str, start: int, end: int) -> list[Fix]:
    """The hints that rewrite the flagged text or the line around it: an operator from
    another language ('and' -> '&&', '=' -> '==' or ':='), infix 'mod', an update's
    'if', an unclosed comment or name, Pmax in a requirement, an int given a double, a
    variable to saturate."""
    hint, flagged = d.hint or "", text[start:end]
    line_end = text.find("\n", end)
    line_end = len(text) if line_end < 0 else line_end
    line_start = text.rfind("\n", 0, start) + 1
    if m := _OPERATOR.search(d.message):
        return [Fix(f"Write '{m[1]}'", ((start, end, m[1]),))]
    if flagged == "=" and "an update is written 'x := value'" in d.message:
        return [Fix("Write ':='", ((start, end, ":="),))]
    if (m := _MOD.search(hint)) and flagged == "mod":
        a, b = m[1], m[2]
        left = text[:start].rstrip()
        right = text[end:].lstrip()
        if left.endswith(a) and right.startswith(b):
            lo = len(left) - len(a)
            hi = end + (len(text[end:]) - len(right)) + len(b)
            return [Fix(f"Write 'mod({a}, {b})'", ((lo, hi, f"mod({a}, {b})"),))]
    if (m := _IF.search(hint)) and flagged == "if":
        head = re.search(rf"\b{re.escape(m[1])}\s*:=", text[line_start:start])
        stop = re.search(r"[,;}]", text[end:line_end])
        if head is not None and stop is not None:
            return [Fix(f"Write '{m[1]} := {m[2]}'", ((line_start + head.start(),
                                                      end + stop.start(),
                                                      f"{m[1]} := {m[2]}"),))]
    if d.code == "E117" and flagged == "/*":
        return [Fix("Close the comment at the end of the line",
                    ((line_end, line_end, " */"),))]
    if d.code == "E117" and flagged == '"':
        # before the declaration's ';' if the line ends with one
        body = text[end:line_end].rstrip()
        at = end + len(body) - 1 if body.endswith(";") else end + len(body)
        return [Fix("Close the name", ((at, at, '"'),))]
    if "without 'max'" in hint or "without 'min'" in hint:
        op = re.match(r"[PR](max|min)", flagged)
        if op is not None:
            return [Fix(f"Remove '{op[1]}'", ((start + 1, start + 4, ""),))]
    if "round it with floor(...) or ceil(...)" in hint:
        return [Fix(f"Write '{f}({flagged})'", ((start, end, f"{f}({flagged})"),))
                for f in ("floor", "ceil")]
    if m := _CLAMP.search(hint):
        decl = re.search(rf"^[ \t]*var\s+{m[1]}\s*:[^;]*?(?=\s*;)", text, re.M)
        if decl is not None and not decl[0].rstrip().endswith("clamp"):
            return [Fix(f"Declare '{m[1]}' with 'clamp'", ((decl.end(), decl.end(), " clamp"),))]
    return []
