"""Navigation: hover, go to definition, references and the outline (document symbols), from
the last text that parsed, mapped to the editor's text through the lines both share."""

from __future__ import annotations

from collections.abc import Sequence

from lsprotocol import types as T

from afsmc.lsp import index as I
from afsmc.lsp.positions import Doc, Shift, new_range, shift_of
from afsmc.lsp.state import AfsmServer, guarded
from afsmc.lsp.worker import in_thread
from afsmc.syntax import ast


def lookup(ls: AfsmServer, uri: str, pos: T.Position
            ) -> tuple[I.Index, I.Occurrence, Shift, Doc] | None:
    """The name at the editor's position, found in the last good parse (through the lines
    both texts share), with the mapping back to the editor's text."""
    st = ls.docs.get(uri)
    if st is None or st.index is None:
        return None
    shift, doc = shift_of(ls, uri, st.index)
    offset = shift.to_old(doc.offset_at_position(pos))
    occ = st.index.at(offset) if offset is not None else None
    return (st.index, occ, shift, doc) if occ is not None else None



@guarded
def hover(ls: AfsmServer, params: T.HoverParams) -> T.Hover | None:
    found = lookup(ls, params.text_document.uri, params.position)
    if found is None:
        return None
    idx, occ, shift, doc = found
    d = idx.definition(occ)
    if d is None:
        return None
    st = ls.docs[params.text_document.uri]
    text = I.hover(d, idx.text, st.model if shift.same else None)
    return T.Hover(contents=T.MarkupContent(kind=T.MarkupKind.Markdown, value=text),
                   range=new_range(shift, doc, occ.start, occ.end))


@guarded
def definition(ls: AfsmServer, params: T.DefinitionParams) -> T.Location | None:
    uri = params.text_document.uri
    found = lookup(ls, uri, params.position)
    if found is None:
        return None
    idx, occ, shift, doc = found
    d = idx.definition(occ)
    if d is None:
        return None
    rng = new_range(shift, doc, d.ident.start, d.ident.end)
    return None if rng is None else T.Location(uri=uri, range=rng)


@guarded
def references(ls: AfsmServer, params: T.ReferenceParams) -> list[T.Location] | None:
    uri = params.text_document.uri
    found = lookup(ls, uri, params.position)
    if found is None:
        return None
    idx, occ, shift, doc = found
    ranges = (new_range(shift, doc, o.start, o.end)
              for o in idx.references(occ.ns, occ.name, params.context.include_declaration))
    return [T.Location(uri=uri, range=r) for r in ranges if r is not None]


_SYMBOL_KINDS = {
    "constant": T.SymbolKind.Constant, "variable": T.SymbolKind.Variable,
    "mode": T.SymbolKind.EnumMember, "formula": T.SymbolKind.Function,
    "action": T.SymbolKind.Method, "hazard": T.SymbolKind.Event, "label": T.SymbolKind.Boolean,
    "rewards": T.SymbolKind.Struct, "property": T.SymbolKind.Property,
    "field": T.SymbolKind.Field,
}


# Declarations in the outline of one document; one more entry says how many are left out.
# The outline of a document of tens of thousands of declarations is a reply of megabytes:
# the client takes seconds to read it, and every reply behind it (a hover on another
# document) waits; no one reads such an outline through.
MAX_SYMBOLS = 1000


@guarded
async def document_symbols(ls: AfsmServer, params: T.DocumentSymbolParams
                           ) -> list[T.DocumentSymbol]:
    """The outline, made off the event loop: the first MAX_SYMBOLS declarations, and an
    entry that says how many more there are (at the first of them)."""
    return list(await in_thread(_document_symbols, ls, params))


def _document_symbols(ls: AfsmServer, params: T.DocumentSymbolParams) -> list[T.DocumentSymbol]:
    uri = params.text_document.uri
    st = ls.docs.get(uri)
    if st is None or st.index is None:
        return []
    idx = st.index
    shift, doc = shift_of(ls, uri, idx)
    by_decl: dict[int, I.Definition] = {
        id(d.decl): d for d in idx.defs.values() if d.kind != "field"}
    out: list[T.DocumentSymbol] = []
    for i, decl in enumerate(idx.module.decls):
        d = by_decl.get(id(decl))
        whole = new_range(shift, doc, decl.span.start, decl.span.end)
        name = new_range(shift, doc, d.ident.start, d.ident.end) if d else None
        if d is None or whole is None or name is None:
            continue  # not declared, or edited since the last good parse
        if len(out) == MAX_SYMBOLS:
            out.append(_left_out(idx.module.decls[i:], by_decl, whole, name))
            break
        children = [
            T.DocumentSymbol(name=f.name.text, kind=T.SymbolKind.Field, range=r, selection_range=n)
            for f in (decl.type.fields if isinstance(decl, ast.VarDecl)
                      and isinstance(decl.type, ast.TupleType) else ())
            for r, n in [(new_range(shift, doc, f.span.start, f.span.end),
                          new_range(shift, doc, f.name.span.start, f.name.span.end))]
            if r is not None and n is not None]
        detail = d.kind
        if isinstance(decl, (ast.ActionDecl, ast.HazardDecl)):
            detail = f"{d.kind} in {idx.text[decl.modes.span.start:decl.modes.span.end]}"
        out.append(T.DocumentSymbol(
            name=d.name, kind=_SYMBOL_KINDS[d.kind], range=whole, selection_range=name,
            detail=detail, children=children or None))
    return out


def _left_out(rest: Sequence[ast.Decl], by_decl: dict[int, I.Definition], whole: T.Range,
              name: T.Range) -> T.DocumentSymbol:
    """The outline's last entry, for the declarations from `rest[0]` on (at `whole`, its
    name at `name`) that it leaves out."""
    n = sum(1 for decl in rest if id(decl) in by_decl)
    return T.DocumentSymbol(
        name=f"{n:,} more declarations are not shown", kind=T.SymbolKind.Namespace,
        range=whole, selection_range=name,
        detail=f"the outline lists the first {MAX_SYMBOLS:,} declarations; workspace symbols "
        "(search by name) find the others")
