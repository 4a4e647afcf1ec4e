"""parse() and parse_property() turn text into the AST, with spans on the source."""

from __future__ import annotations

import pytest

from afsmc.diagnostics import BOM, CompileError
from afsmc.syntax import ast
from afsmc.syntax.parser import MAX_DEPTH, parse, parse_property

SMALL = """\
machine demo;
const double P = 0.25;
var x : [0..3] init 0 clamp;
mode Idle = 0 initial;
mode Done = 1 final;
action Go in Idle when x < 3 weight 2 {
    P: x += 1;
    1 - P: goto Done;
}
label done = mode == Done;
property reach = P=? [ F<=10 "done" ];
"""


def test_a_small_module_gives_one_node_per_declaration() -> None:
    module = parse(SMALL, "demo.afsm")
    assert module.machine is not None and module.machine.name.text == "demo"
    kinds = [type(d).__name__ for d in module.decls]
    assert kinds == ["ConstDecl", "VarDecl", "ModeDecl", "ModeDecl", "ActionDecl",
                     "LabelDecl", "PropertyDecl"]


def test_declarations_keep_what_was_written() -> None:
    const, var, idle, done, go, label, prop = parse(SMALL).decls
    assert isinstance(const, ast.ConstDecl) and const.type == "double"
    assert isinstance(const.value, ast.Num) and const.value.value == 0.25
    assert isinstance(var, ast.VarDecl) and var.clamp
    assert isinstance(var.type, ast.RangeType) and isinstance(var.init, ast.Num)
    assert isinstance(idle, ast.ModeDecl) and (idle.number, idle.initial, idle.final) == (0, True, False)
    assert isinstance(done, ast.ModeDecl) and (done.number, done.final) == (1, True)
    assert isinstance(label, ast.LabelDecl) and isinstance(label.value, ast.Binary)
    assert isinstance(label.value.left, ast.ModeRef) and label.value.op == "=="
    assert isinstance(prop, ast.PropertyDecl) and isinstance(prop.query, ast.PQuery)
    path = prop.query.path
    assert isinstance(path, ast.Eventually) and isinstance(path.bound, ast.Num)
    assert isinstance(path.target, ast.LabelRef) and path.target.name == "done"
    assert isinstance(go, ast.ActionDecl)


def test_an_action_has_its_guard_weight_and_outcomes() -> None:
    go = parse(SMALL).decls[4]
    assert isinstance(go, ast.ActionDecl)
    assert go.name.text == "Go"
    assert [type(i).__name__ for i in go.modes.items] == ["ModeName"] and not go.modes.every
    assert isinstance(go.guard, ast.Binary) and go.guard.op == "<"
    assert isinstance(go.weight, ast.Num) and go.weight.value == 2
    first, second = go.body.outcomes
    assert isinstance(first.prob, ast.Name) and first.prob.name.text == "P"
    (inc,) = first.updates
    assert isinstance(inc, ast.Assign) and inc.op == "+=" and inc.target.name.text == "x"
    assert isinstance(second.prob, ast.Binary) and second.prob.op == "-"
    (goto,) = second.updates
    assert isinstance(goto, ast.Goto) and goto.mode.text == "Done"


def test_spans_point_at_the_source() -> None:
    module = parse(SMALL, "demo.afsm")
    assert module.span.start == 0 and module.span.end == len(SMALL)
    go = module.decls[4]
    assert isinstance(go, ast.ActionDecl)
    assert SMALL[go.span.start:go.span.end].startswith("action Go in Idle")
    assert SMALL[go.span.start:go.span.end].endswith("}")
    assert (go.name.span.line, go.name.span.column) == (6, 8)
    assert go.name.span.source.path == "demo.afsm"
    assert go.guard is not None and SMALL[go.guard.span.start:go.guard.span.end] == "x < 3"


def test_plain_statements_of_a_body_are_one_certain_outcome() -> None:
    module = parse("mode A initial;\naction Go in A { goto A; x := 1; }\n")
    go = module.decls[1]
    assert isinstance(go, ast.ActionDecl)
    (outcome,) = go.body.outcomes
    assert outcome.prob is None
    assert [type(u).__name__ for u in outcome.updates] == ["Goto", "Assign"]


def test_operators_bind_as_the_grammar_says() -> None:
    label = parse("label l = a || b && !c => d;").decls[0]
    assert isinstance(label, ast.LabelDecl)
    top = label.value
    assert isinstance(top, ast.Binary) and top.op == "=>"
    assert isinstance(top.left, ast.Binary) and top.left.op == "||"
    right = top.left.right
    assert isinstance(right, ast.Binary) and right.op == "&&"
    assert isinstance(right.right, ast.Unary) and right.right.op == "!"


def test_a_negative_literal_is_folded_into_the_number() -> None:
    formula = parse("formula f = -2;").decls[0]
    assert isinstance(formula, ast.FormulaDecl)
    assert isinstance(formula.value, ast.Num)
    assert (formula.value.value, formula.value.text) == (-2, "-2")


def test_a_byte_order_mark_keeps_the_offsets() -> None:
    module = parse(BOM + "machine m;\n")
    assert module.machine is not None
    assert module.machine.name.span.start == len(BOM + "machine ")


def test_parse_property_parses_one_formula() -> None:
    query = parse_property('Rmin=? [ F "done" ]')
    assert isinstance(query, ast.RQuery) and query.opt == "min"
    assert isinstance(query.path, ast.ReachReward)
    p = parse_property('P=? [ "a" U<=5 "b" ]')
    assert isinstance(p, ast.PQuery) and isinstance(p.path, ast.Until)
    assert isinstance(p.path.bound, ast.Num) and p.path.bound.value == 5


def test_an_expression_nested_too_deeply_is_refused() -> None:
    text = "formula f = " + " + ".join(["1"] * (MAX_DEPTH + 2)) + ";"
    with pytest.raises(CompileError) as err:
        parse(text)
    (diag,) = err.value.diagnostics
    assert diag.code == "E113"
    assert diag.span is not None and diag.span.start == len("formula f = ")


def test_mistakes_seen_once_a_rule_is_built_are_reported() -> None:
    with pytest.raises(CompileError) as err:
        parse("mode A initial initial;\naction Go in A { }\n")
    codes = [d.code for d in err.value.diagnostics]
    assert codes == ["E118", "E119"]
