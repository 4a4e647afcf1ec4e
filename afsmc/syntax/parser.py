"""Parsing: text -> :class:`afsmc.syntax.ast.Module` (or one property), or a CompileError
with one syntax diagnostic written for people.

The stages of a parse: lark's LALR parser gives a tree (afsmc.syntax.grammar); an
expression nested too deeply is refused (E113) before the recursive tree -> AST step
(afsmc.syntax.build) could overflow the stack; a syntax error is explained by
afsmc.syntax.errors.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any, cast

import lark
from lark import Token
from lark.exceptions import UnexpectedInput

from afsmc.diagnostics import BOM, CompileError, Reporter, Source, Span, codes
from afsmc.syntax import ast
from afsmc.syntax.build import Builder
from afsmc.syntax.errors.diagnose import report_glued_keyword, report_syntax_error
from afsmc.syntax.grammar import GluedKeyword, parse_tree

# How deeply an expression may nest: each operator of a chain `a + b + c ...` (or `- - x`,
# `!!b`, ...) is one level. Every stage walks expressions recursively; afsmc.stack gives them
# the stack for this (E113 beyond it).
MAX_DEPTH = 5000
# The grammar's expression rules (the ones that build an operator node).
_EXPR_RULES = frozenset({"arith", "compare", "and_", "or_", "implies", "ite", "neg", "not_",
                         "call", "mode_in"})


def parse(text: str, path: str = "<input>") -> ast.Module:
    """Parse one file. Raises CompileError with a single syntax diagnostic on failure."""
    return _parse_module(text, path)


# The AST is immutable, and a sweep loads one text at every value of a constant (0.2 s of
# the UAV's 0.25 s load is parsing): the last few parses are kept.
@lru_cache(maxsize=4)
def _parse_module(text: str, path: str) -> ast.Module:
    return cast(ast.Module, _parse(text, path, "start"))


def parse_property(text: str, path: str = "--formula") -> ast.PQuery | ast.RQuery:
    """Parse one property formula on its own (`P=? [ F "done" ]`), so that a syntax error
    speaks only of the formula. Raises CompileError like :func:`parse`."""
    return cast("ast.PQuery | ast.RQuery", _parse(text, path, "prop"))


def _parse(text: str, path: str, start: str) -> Any:
    source = Source(path, text)
    reporter = Reporter()
    try:
        # A leading byte-order mark lexes as a blank, which keeps every offset as in `text`.
        tree = parse_tree(" " + text[1:] if text.startswith(BOM) else text, start)
    except GluedKeyword as exc:
        report_glued_keyword(exc.token, source, reporter)
        raise CompileError(reporter.diagnostics) from None
    except UnexpectedInput as exc:
        report_syntax_error(exc, source, reporter, formula=start == "prop")
        raise CompileError(reporter.diagnostics) from None
    if _too_deep(tree, source, reporter):
        raise CompileError(reporter.diagnostics)
    try:
        node = Builder(source, reporter).transform(tree)
    except lark.exceptions.VisitError as exc:
        if isinstance(exc.orig_exc, CompileError):
            raise exc.orig_exc from None
        raise
    if reporter.has_errors:
        raise CompileError(reporter.diagnostics)
    return node


def _too_deep(tree: lark.Tree[Token], source: Source, reporter: Reporter) -> bool:
    """E113 for each expression nested deeper than MAX_DEPTH (iterative, before the
    recursive tree-to-AST step would fail on it)."""
    # (node, its depth within the outermost expression around it, that expression)
    stack: list[tuple[lark.Tree[Token], int, lark.Tree[Token] | None]] = [(tree, 0, None)]
    reported: set[int] = set()
    while stack:
        node, depth, top = stack.pop()
        if node.data in _EXPR_RULES:
            top = top or node
            depth += 1
        if depth > MAX_DEPTH and top is not None:
            if id(top) not in reported:
                reported.add(id(top))
                reporter.error(
                    codes.E113, f"this expression nests more than {MAX_DEPTH} levels deep",
                    Span.at_offset(source, top.meta.start_pos),
                    hint=f"afsmc supports expressions up to {MAX_DEPTH} levels: each operator "
                    "of a chain like 'a + b + c' or '- - x' is one; shorten it (e.g. "
                    "'x * 0.1 + x * 0.1' is 'x * 0.2')")
            continue
        stack.extend((c, depth, top) for c in node.children if isinstance(c, lark.Tree))
    return bool(reported)
