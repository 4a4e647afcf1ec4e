"""The tolerant scanner: token positions, one-line quotes, and what precedes an offset,
also in text that does not lex."""

from __future__ import annotations

from afsmc.diagnostics import BOM
from afsmc.syntax.scan import flat_text, scan, string_end, tokens


def _words(text: str, start: int = 0, end: int | None = None) -> list[str]:
    return [text[i:j] for i, j in tokens(text, start, end)]


def test_tokens_skip_blanks_and_comments() -> None:
    text = "label a = x // trailing\n  /* block\n */ == 1;"
    assert _words(text) == ["label", "a", "=", "x", "=", "=", "1", ";"]


def test_tokens_give_offsets_into_the_text() -> None:
    text = "var  x_1 : [0..3];"
    spans = list(tokens(text))
    assert spans[:3] == [(0, 3), (5, 8), (9, 10)]
    assert all(text[i:j].strip() == text[i:j] for i, j in spans)


def test_a_quoted_label_is_one_token() -> None:
    text = 'P=? [ F "all \\" done" ]'
    assert '"all \\" done"' in _words(text)


def test_tokens_go_on_through_text_that_does_not_lex() -> None:
    assert _words("x := 1 @ % y") == ["x", ":", "=", "1", "@", "%", "y"]
    # an unclosed comment runs to the end of the text; an unclosed label to the end of
    # its line, the newline included
    assert _words("a /* never closed") == ["a"]
    assert _words('a "open\nb') == ["a", '"open\n', "b"]


def test_tokens_keep_to_the_range_and_skip_a_byte_order_mark() -> None:
    text = BOM + "machine m;"
    assert _words(text) == ["machine", "m", ";"]
    assert _words("abcdef ghi", 2, 8) == ["cdef", "g"]


def test_string_end_stops_at_the_quote_or_the_line() -> None:
    assert string_end('"abc" x', 0) == 4
    assert string_end('"a\\"b" x', 0) == 5
    assert string_end('"abc\nx"', 0) == 4
    assert string_end('"abc', 0) == 4


def test_flat_text_puts_a_region_on_one_line() -> None:
    text = 'P=? [ F   "done"\n   // why\n   ]'
    assert flat_text(text, 0, len(text)) == ('P=? [ F "done" ]', None)


def test_flat_text_keeps_tokens_that_touch_together() -> None:
    assert flat_text("x+1 ==  2", 0, 9)[0] == "x+1 == 2"


def test_flat_text_maps_a_site_into_the_flattened_text() -> None:
    text = "a  &&\n  b"
    out, site = flat_text(text, 0, len(text), (3, 5))
    assert out == "a && b"
    # the site starts with the gap before its first token, and ends before the gap after it
    assert site == (1, 4)
    assert out[1:4] == " &&"


def test_scan_tracks_open_brackets_and_the_last_token() -> None:
    text = "action A in S {\n    0.5: x := (1 + [2"
    result = scan(text, len(text))
    assert [c for c, _ in result.open] == ["{", "(", "["]
    assert [text[at] for _, at in result.open] == ["{", "(", "["]
    assert result.last_end == len(text)


def test_scan_closes_brackets_in_order() -> None:
    text = "a { b ( c ) d } e ( f"
    result = scan(text, len(text))
    assert result.open == [("(", text.rindex("("))]


def test_scan_records_the_first_token_of_each_line() -> None:
    text = "mode A;\n\n  action Go in A {\n goto A;"
    result = scan(text, len(text))
    assert result.line_heads == {1: (0, "mode"), 3: (11, "action"), 4: (29, "goto")}


def test_scan_stops_at_the_offset() -> None:
    text = "label a = (x; label b"
    upto = text.index(";")
    result = scan(text, upto)
    assert result.last_end == upto
    assert [c for c, _ in result.open] == ["("]
