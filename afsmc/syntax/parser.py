"""Parsing: text -> :class:`afsmc.syntax.ast.Module` (or one property), or a CompileError
with one syntax diagnostic written for people.

The stages of a parse: a text larger than MAX_SOURCE_CHARS is refused (E004); lark's LALR
parser gives a tree (afsmc.syntax.grammar), and stops at an expression nested too deeply
(E113) before the recursive tree -> AST step (afsmc.syntax.build) could overflow the stack;
a syntax error is explained by afsmc.syntax.errors.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, cast

from lark.exceptions import UnexpectedInput

from afsmc.diagnostics import BOM, CompileError, Diagnostic, Reporter, Severity, Source, Span, codes
from afsmc.heap import collector_paused
from afsmc.syntax import ast
from afsmc.syntax.build import Builder
from afsmc.syntax.errors.diagnose import report_glued_keyword, report_syntax_error
from afsmc.syntax.grammar import GluedKeyword, TooDeep, parse_fast, parse_tree
from afsmc.syntax.limits import MAX_DEPTH, MAX_SOURCE_CHARS

__all__ = ["MAX_DEPTH", "parse", "parse_property", "too_large"]


def parse(text: str, path: str = "<input>") -> ast.Module:
    """Parse one file. Raises CompileError with a single syntax diagnostic on failure."""
    return _parse_module(text, path)


# The AST is immutable, and a sweep loads one text at every value of a constant (0.2 s of
# the UAV's 0.25 s load is parsing): the last few parses are kept.
@lru_cache(maxsize=4)
def _parse_module(text: str, path: str) -> ast.Module:
    with collector_paused():
        return cast(ast.Module, _parse(text, path, "start"))


def parse_property(text: str, path: str = "--formula") -> ast.PQuery | ast.RQuery:
    """Parse one property formula on its own (`P=? [ F "done" ]`), so that a syntax error
    speaks only of the formula. Raises CompileError like :func:`parse`."""
    return cast("ast.PQuery | ast.RQuery", _parse(text, path, "prop"))


def _parse(text: str, path: str, start: str) -> Any:
    source = Source(path, text)
    reporter = Reporter()
    if len(text) > MAX_SOURCE_CHARS:
        raise CompileError([too_large(source)])
    # A leading byte-order mark lexes as a blank, which keeps every offset as in `text`.
    body = " " + text[1:] if text.startswith(BOM) else text
    fast = Builder(source, Reporter())
    node = parse_fast(body, start, fast)
    if node is not None:
        if fast.reporter.has_errors:
            raise CompileError(fast.reporter.diagnostics)
        return node
    try:
        tree = parse_tree(body, start)
    except GluedKeyword as exc:
        report_glued_keyword(exc.token, source, reporter)
        raise CompileError(reporter.diagnostics) from None
    except UnexpectedInput as exc:
        report_syntax_error(exc, source, reporter, formula=start == "prop")
        raise CompileError(reporter.diagnostics) from None
    except TooDeep as exc:
        reporter.error(
            codes.E113, f"this expression nests more than {MAX_DEPTH} levels deep",
            Span.at_offset(source, exc.start),
            hint=f"afsmc supports expressions up to {MAX_DEPTH} levels: each operator of a "
            "chain like 'a + b + c' or '- - x' is one; shorten it (e.g. 'x * 0.1 + x * 0.1' "
            "is 'x * 0.2')")
        raise CompileError(reporter.diagnostics) from None
    node = Builder(source, reporter).build(tree)
    if reporter.has_errors:
        raise CompileError(reporter.diagnostics)
    return node


def too_large(source: Source) -> Diagnostic:
    """E004 for a text beyond MAX_SOURCE_CHARS (an editor's buffer, standard input)."""
    return Diagnostic(
        codes.E004, Severity.ERROR, f"{source.path} has {len(source.text):,} characters; afsmc "
        f"reads files of up to {MAX_SOURCE_CHARS:,}", Span.at_offset(source, 0, 0),
        hint="split the model, or generate it with fewer declarations (a specification of "
        "this size is not checked in reasonable time)")
