"""Inputs at the edges of what afsmc accepts: byte-order marks, argument files, repeated
or non-finite constants, numbers beyond 64 bits, names PRISM or Storm reserve."""

from __future__ import annotations

import math
import os
import re
from pathlib import Path

import pytest
import stormpy

from afsmc.cli import build_parser
from afsmc.commands.common import overrides
from afsmc.commands.sweep import split_consts
from afsmc.compiler import load
from afsmc.lower.lowering import lower
from afsmc.model.names import RESERVED, STORM_KEYWORDS
from afsmc.model.pretty import number
from afsmc.syntax.fmt import format_text
from afsmc.text import count
from afsmc.verify.sweep_values import parse_values
from tests.conftest import EXAMPLES, run_cli
from tests.storm_util import storm_prism

BOM = "\ufeff"

SMALL = """machine small;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
action Up in A when x < 3 { x += 1; }
action Done in A when x == 3 { goto B; }
label done = mode == B;
property reach = P=? [ F "done" ];
"""


def test_a_leading_byte_order_mark_is_skipped(tmp_path: Path) -> None:
    path = tmp_path / "bom.afsm"
    path.write_text(BOM + SMALL, encoding="utf-8")
    assert run_cli("check", str(path)).code == 0
    bad = tmp_path / "bad.afsm"
    bad.write_text(BOM + "const int 5;\n", encoding="utf-8")
    r = run_cli("check", str(bad))
    assert r.code == 1 and f"{bad}:1:11: error[E101]: unexpected '5'" in r.err
    assert "\n 1 | const int 5;\n   |           ^\n" in r.err


def test_fmt_keeps_a_byte_order_mark() -> None:
    out = format_text(BOM + "machine  small ;\n" + SMALL.split("\n", 1)[1])
    assert out.startswith(BOM + "machine small;\n") and out.count(BOM) == 1
    assert format_text(out) == out


def test_a_constant_given_twice_is_a_usage_error() -> None:
    for argv in (["--const", "CELLS=3,CELLS=4"], ["--const", "CELLS=3", "-c", "CELLS=5"]):
        r = run_cli("check", str(EXAMPLES / "patrol.afsm"), *argv)
        assert r.code == 2 and "--const CELLS is given twice" in r.err, r.err


def test_a_constant_without_a_name_is_a_usage_error() -> None:
    for value in ("=3", "CELLS=3,=4", " =3"):
        r = run_cli("check", str(EXAMPLES / "patrol.afsm"), "--const", value)
        assert r.code == 2 and "expected NAME=VALUE" in r.err and "(no name)" in r.err, r.err


def test_a_constant_without_a_value_is_a_usage_error() -> None:
    # as `--const CELLS` is (no '='): both are the option's own syntax, not the model's
    for command in ("check", "verify", "sweep"):
        for value in ("CELLS=", "CELLS= ", "ROUNDS=1:2,CELLS="):
            r = run_cli(command, str(EXAMPLES / "patrol.afsm"), "--const", value)
            assert r.code == 2 and "expected NAME=VALUE" in r.err and "(no value)" in r.err, \
                r.err


def test_sweep_a_range_replaces_a_preset_value_but_not_a_second_value() -> None:
    fixed, swept = split_consts(["OBJECTS=2", "DEADLINE=500", "DEADLINE=150:500:50"])
    assert fixed == {"OBJECTS": "2"} and swept == {"DEADLINE": [150, 200, 250, 300, 350, 400, 450, 500]}
    assert split_consts(["N=2,T=0:10:5", "M=1"]) == ({"N": "2", "M": "1"}, {"T": [0, 5, 10]})
    for items in (["N=1", "N=2"], ["N=1,N=2"], ["T=1:3", "T=4,5"]):
        with pytest.raises(SystemExit) as exc:
            split_consts(items)
        assert exc.value.code == 2


def test_argument_files_are_split_like_a_shell(tmp_path: Path) -> None:
    args = tmp_path / "a.args"
    args.write_text('# a preset\n--const "CELLS=2"  # quoted\n--const ROUNDS=1 --engine sparse\n'
                    "--formula 'P=? [ F \"done\" ]'\n")
    ns = build_parser().parse_args(["verify", "examples/patrol.afsm", f"@{args}"])
    assert overrides(ns) == {"CELLS": "2", "ROUNDS": "1"}
    assert ns.engine == "sparse" and ns.formula == ['P=? [ F "done" ]']
    assert run_cli("check", str(EXAMPLES / "patrol.afsm"), f"@{args}").code == 2  # --formula: verify's
    ok = tmp_path / "ok.args"
    ok.write_text('--const "CELLS=2"\n')
    assert run_cli("check", str(EXAMPLES / "patrol.afsm"), f"@{ok}").code == 0
    bad = tmp_path / "bad.args"
    bad.write_text('--const "CELLS=2\n')
    r = run_cli("check", str(EXAMPLES / "patrol.afsm"), f"@{bad}")
    assert r.code == 2 and "No closing quotation" in r.err


def test_an_argument_file_that_includes_itself_is_a_usage_error(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """argparse expands @FILE inside argument files; a cycle would recurse until Python's
    limit (a traceback). Nested files without a cycle, and one file used twice side by
    side, still work."""
    (tmp_path / "self.args").write_text("@self.args\n")
    (tmp_path / "a.args").write_text("@b.args\n")
    (tmp_path / "b.args").write_text("--const CELLS=2\n@a.args\n")
    (tmp_path / "c.args").write_text("--engine sparse\n")
    (tmp_path / "d.args").write_text("--const CELLS=2\n@c.args\n")
    patrol = str(EXAMPLES / "patrol.afsm")
    monkeypatch.chdir(tmp_path)  # nested @files are read relative to the working directory
    for name, chain in (("self.args", "self.args"), ("a.args", "a.args -> b.args")):
        r = run_cli("check", patrol, f"@{name}")
        assert r.code == 2 and "Traceback" not in r.err, r.err
        assert f"includes itself (through {chain})" in r.err, r.err
    ns = build_parser().parse_args(["verify", patrol, "@d.args", "@c.args"])
    assert overrides(ns) == {"CELLS": "2"} and ns.engine == "sparse"


def test_the_scenario_presets_still_read() -> None:
    ns = build_parser().parse_args(["verify", "examples/uav.afsm", f"@{EXAMPLES / 'uav-scenario1.args'}"])
    assert overrides(ns) == {"OBJECTS": "3", "T_LIMIT": "900", "DEADLINE": "900", "WIDTH": "7",
                             "HEIGHT": "7", "ALPHA": "0.085"}


WEIGHTED = """machine weighted;
param double D = 0.5;
param int N = 3;
var x : [0..3] init 0;
mode A = 0 initial;
mode B = 1 final;
action Up in A when x < 3 && x < N weight D { x += 1; }
action Done in A when x >= 3 || x >= N { goto B; }
label done = mode == B;
property reach = P=? [ F "done" ];
"""


@pytest.mark.parametrize("value", ["inf", "-inf", "1e400", "nan", "NaN", "infinity"])
def test_a_non_finite_double_on_the_command_line_is_e208(tmp_path: Path, value: str) -> None:
    path = tmp_path / "weighted.afsm"
    path.write_text(WEIGHTED)
    for argv in (["check"], ["compile", "-o", "-"]):
        r = run_cli(*argv, str(path), "--const", f"D={value}")
        assert r.code == 1, r.err
        assert f"{path}:2:14: error[E208]: --const D={value}: not a finite double" in r.err
        assert "Traceback" not in r.err and "E302" not in r.err


def test_an_integer_beyond_64_bits_on_the_command_line_is_e208(tmp_path: Path) -> None:
    path = tmp_path / "weighted.afsm"
    path.write_text(WEIGHTED)
    r = run_cli("check", str(path), "--const", "N=10000000000000000000")
    assert r.code == 1 and "error[E208]: --const N=10000000000000000000: does not fit in a " \
        "64-bit integer (-9223372036854775808 to 9223372036854775807)" in r.err
    assert run_cli("check", str(path), "--const", "N=9223372036854775807").code == 0


def test_printing_never_fails_on_a_non_finite_double() -> None:
    assert [number(v) for v in (math.inf, -math.inf, math.nan, 1e300, 2.0)] == \
        ["inf", "-inf", "nan", "1e+300", "2.0"]


def test_huge_state_counts_read_as_powers_of_ten() -> None:
    assert [count(n) for n in (12_345_678, 2.5e9, 2e19, 2 * 10**400, math.inf)] == \
        ["12.3 M", "2.5 G", "2.0e19", "2.0e400", "inf"]


def test_sweep_values_must_be_finite() -> None:
    for text in ("inf,1", "nan", "0:inf:1", "0:1:nan"):
        with pytest.raises(ValueError, match="finite"):
            parse_values(text)


@pytest.mark.parametrize("stem", ["init", "module", "true", "rewards", "dtmc", "floor", "F", "9lives",
                                  "café-1"])
def test_a_machine_named_by_its_file_gets_a_name_storm_reads(tmp_path: Path, stem: str) -> None:
    """Without a `machine` line the module is named after the file; a user cannot be
    blamed for the file's name, so it is made safe rather than refused."""
    path = tmp_path / f"{stem}.afsm"
    path.write_text(SMALL.split("\n", 1)[1])
    model = load(str(path)).model
    assert model.name.isascii() and model.name.isidentifier() and model.name not in RESERVED
    _, values = storm_prism(lower(model), tmp_path)
    assert values == {"reach": 1.0}


def test_storm_refuses_the_names_afsmc_reserves_for_it(tmp_path: Path) -> None:
    """The lists in afsmc.model.names are not stale: Storm's PRISM parser refuses its own
    keywords and PRISM's as a module name (player/endplayer: newer Storm releases only)."""
    names = [*sorted(STORM_KEYWORDS - {"player", "endplayer"}), "init", "module", "true", "dtmc"]
    refused = []
    for name in names:
        path = tmp_path / f"{name}.prism"
        path.write_text(f"dtmc\nmodule {name}\n  x : [0..1] init 0;\n  [] x = 0 -> (x'=1);\nendmodule\n")
        try:
            stormpy.parse_prism_program(str(path))
        except RuntimeError:
            refused.append(name)
    assert refused == names


def test_a_comment_between_a_policy_minus_and_its_number_keeps_the_number() -> None:
    # Found by the grammar fuzzer: the number was read from the source text, comment and all.
    from afsmc.syntax import ast
    from afsmc.syntax.parser import parse

    def policy(text: str) -> list[float]:
        module = parse("machine m;\nconst int a = 3 from sim uav.move.duration with "
                       f"confidence = {text};\n", "m.afsm")
        decl = module.decls[0]
        assert isinstance(decl, ast.ConstDecl) and decl.source is not None
        return [value for _, value in decl.source.policy]

    assert policy("- // c\n 0.5") == policy("- /* c */ 0.5") == policy("-0.5") == [-0.5]


@pytest.mark.parametrize("before", ["\t", "\t  ", "漢字 ", "é"])
def test_the_caret_sits_under_the_mistake_after_tabs_and_wide_characters(
        tmp_path: Path, before: str) -> None:
    path = tmp_path / "t.afsm"
    path.write_text("machine t;\nmode A = 0 initial;\n"
                    f"action Go in A when /*{before}*/\tx > 0 {{ goto A; }}\n", encoding="utf-8")
    r = run_cli("check", str(path))
    assert r.code == 1 and "error[E203]" in r.err, r.err
    lines = r.err.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(" 3 | "))
    shown, caret = lines[i][len(" 3 | "):], lines[i + 1][len(" 3 | "):]
    assert "\t" not in shown and caret.strip() == "^"
    # the caret's terminal column is that of the x (wide characters take two columns)
    col = sum(2 if "\u4e00" <= c <= "\u9fff" else 1 for c in shown[:shown.index("x > 0")])
    assert len(caret) - 1 == col


@pytest.mark.parametrize(("name", "value"), [("N", "1_0"), ("N", "١٢"), ("D", "0_5"),
                                             ("D", "٠.٥"), ("N", "0x10")])
def test_numbers_on_the_command_line_are_written_as_in_the_language(
        tmp_path: Path, name: str, value: str) -> None:
    # Python's int() and float() read digit separators and non-ASCII digits; afsm does not.
    path = tmp_path / "weighted.afsm"
    path.write_text(WEIGHTED)
    r = run_cli("check", str(path), "--const", f"{name}={value}")
    assert r.code == 1 and f"error[E208]: --const {name}={value}: not a" in r.err, r.err
    for ok in ("N=+3", "D=.5", "D=5e-1", "D=0."):
        assert run_cli("check", str(path), "--const", ok).code == 0, ok


def test_compile_to_an_empty_output_name_is_a_usage_error(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # `-o ''` wrote ./.prism and ./.props, hidden files named by the suffix alone.
    monkeypatch.chdir(tmp_path)
    r = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-o", "")
    assert r.code == 2 and "-o: an empty name" in r.err, r.err
    assert list(tmp_path.iterdir()) == []


def test_a_bug_in_afsmc_is_one_line_and_a_traceback_file(monkeypatch: pytest.MonkeyPatch) -> None:
    """An exception that escapes a command is afsmc's bug, not the user's: exit 3, one line
    on stderr naming a file that holds the traceback, and no traceback on the terminal."""
    import afsmc.commands.check as check

    def broken(args: object) -> int:
        raise ValueError("an impossible state")

    monkeypatch.delenv("AFSMC_TRACEBACK", raising=False)
    monkeypatch.setattr(check, "run", broken)
    result = run_cli("check", "examples/patrol.afsm")
    assert result.code == 3
    assert "Traceback" not in result.err
    match = re.search(r"internal error .*ValueError: an impossible state; the traceback is in "
                      r"(\S+); please report it", result.err)
    assert match, result.err
    saved = Path(match.group(1))
    try:
        text = saved.read_text()
        assert "Traceback" in text and "an impossible state" in text
    finally:
        saved.unlink()


def test_an_output_that_is_a_device_or_pipe_is_written_into_not_replaced(tmp_path: Path) -> None:
    """`sweep -o /dev/null` renamed its temporary file over /dev/null: the machine's
    /dev/null became a regular file. A FIFO stands in for the device here."""
    import os
    import stat
    import threading

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()), daemon=True)
    reader.start()
    r = run_cli("sweep", str(EXAMPLES / "patrol.afsm"), "--const", "CELLS=1:2", "-p", "finish",
                "--jobs", "1", "-o", str(fifo))
    reader.join(timeout=60)
    assert r.code == 0, r.err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)  # still the pipe, not a file put in its place
    assert got and got[0].decode().startswith("CELLS,property,min,max")
    r = run_cli("compile", str(EXAMPLES / "patrol.afsm"), "-o", str(fifo))
    assert r.code == 2 and "not a directory or a regular file" in r.err


@pytest.mark.parametrize("command", [
    ["simulate", "--runs", "50", "--json"], ["simulate", "--runs", "50"],
    ["sweep", "--bound", "0:4", "-p", "finish_soon"], ["compile", "-o", "-"]])
@pytest.mark.parametrize("stdout", ["full", "closed"])
def test_results_that_cannot_reach_stdout_are_e003(command: list[str], stdout: str) -> None:
    """A full disk behind stdout was a traceback (--json) or 'internal error' (exit 3); a
    closed stdout was exit 3 (sweep) or exit 0 with the results silently lost (simulate).
    Review 14, with /dev/full standing in for the full disk."""
    import subprocess
    import sys

    from tests.conftest import EXAMPLES

    argv = [sys.executable, "-m", "afsmc.cli", command[0], str(EXAMPLES / "patrol.afsm"),
            *command[1:]]
    if stdout == "full":
        with open("/dev/full", "w") as full:
            r = subprocess.run(argv, stdout=full, stderr=subprocess.PIPE, text=True,
                               timeout=300)
        why = "No space left on device"
    else:
        # the child starts with descriptor 1 closed
        r = subprocess.run(argv, stderr=subprocess.PIPE, text=True, timeout=300,
                           preexec_fn=lambda: os.close(1))
        why = "standard output is closed"
    assert r.returncode == 1, r.stderr
    assert f"error[E003]: cannot write to standard output: {why}" in r.stderr, r.stderr
    assert "Traceback" not in r.stderr and "internal error" not in r.stderr


def test_a_byte_that_is_not_utf8_is_shown_at_its_line(tmp_path: Path) -> None:
    """A Latin-1 'é' gave E001 "is not UTF-8 text" with no line or column (review 18)."""
    from tests.conftest import run_cli

    path = tmp_path / "lat.afsm"
    path.write_bytes(b"machine m;\n// caf\xe9\nmode A = 0 initial;\n")
    r = run_cli("check", str(path))
    assert r.code == 1 and f"{path}:2:7: error[E001]: cannot read {path}: byte 0xe9 is not " \
        "UTF-8 text" in r.err, r.err
    assert "save the file as UTF-8" in r.err and "Traceback" not in r.err


def test_compile_resolve_takes_floor_and_ceil_as_simulate_does() -> None:
    """Review 20: `simulate --resolve floor` worked, `compile --resolve floor` was refused.
    The aliases give the same model as lo/hi, and the header says which end."""
    patrol = str(EXAMPLES / "patrol.afsm")
    for alias, end in (("floor", "lo"), ("ceil", "hi")):
        a = run_cli("compile", patrol, "--resolve", alias, "-o", "-")
        b = run_cli("compile", patrol, "--resolve", end, "-o", "-")
        assert a.code == b.code == 0 and a.out == b.out, a.err
        assert ("by their floor" if alias == "floor" else "by their ceiling") in a.out
