"""How the time to parse, check and format a specification grows with its size.

    .venv/bin/python benchmarks/input_scaling.py [--repeat N] [--scale K] [--only SHAPE]

Three shapes of input, each generated at a base size (x1) and ten times it (x10):

- **declarations**: a mission of n modes in a chain, each with a constant, a formula, a
  label and an action (the many-declarations file);
- **long names**: 60 such blocks with every name padded to L characters (L = 100, 1000:
  names are limited to 1,000 characters, E125);
- **long expression**: one guard that sums n terms, in groups of 100 in brackets (an
  expression nests at most 5,000 levels, E113, so a longer one is a sum of sums).

With `--four`, the issue-51 table: each stage at four sizes (x1, x2, x4, x8) and the slope
of log(time) against log(size) (1.0: linear; 2.0: quadratic):

- **check / compile (PRISM)**: `afsmc check` and `afsmc compile` of the declarations
  file, as commands (CPU time of the child process, start-up included);
- **JANI**: `afsmc compile -t jani` of examples/overtake.afsm with an n-term sum in a guard
  (CPU time and the file's bytes);
- **fmt**: `afsmc fmt` of the declarations file;
- **explorer**: `verify examples/patrol.afsm --const CELLS=n` by the default route and with
  `--solver topological` (benchmarks/patrol_chain.py's runs);
- **language server**: a document of n unused constants (n W304 warnings) opened in the
  real server: the time to its diagnostics, and the hover round trips on a small document
  meanwhile (median and max).

`--only` picks stages by name there too.

With `--mb`, only the issue's goal: `check`'s work on a declarations file of 1 MB
(MB_MODES modes, 1,019,904 characters), to be answered in under 10 s.

And the refusals, which must stay fast however large the input: a syntax error after a
name of n characters, a chain `1+1+...` of n terms (E113 after 5,000), a number of n
digits (E125), a file beyond the size limit (E004).

Each time is the CPU time of this process (`time.process_time`, the median of N runs after
a warm-up), so that other work on the machine inflates it less than the wall clock; the
ratio is x10's time over x1's. "check" is `afsmc check`'s work in process (parse, resolve,
the checks); "fmt" is `afsmc fmt`'s (parse, lay out, parse the result again to verify
it). docs/benchmarks.md ("Input size scaling") records the figures.
"""

from __future__ import annotations

import argparse
import asyncio
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.setrecursionlimit(100_000)  # as afsmc.cli gives its commands (afsmc.stack)

from afsmc.compiler import load  # noqa: E402
from afsmc.diagnostics import CompileError  # noqa: E402
from afsmc.syntax import parser  # noqa: E402
from afsmc.syntax.fmt import format_text  # noqa: E402
from afsmc.syntax.limits import MAX_SOURCE_CHARS  # noqa: E402


def declarations(n: int, pad: int = 0) -> str:
    """A chain of n modes, each with a constant, a formula, a label and an action; every
    name padded to `pad` characters."""
    def name(kind: str, i: int) -> str:
        base = f"{kind}{i}"
        return base + "_" * max(0, pad - len(base))
    lines = ["machine big;", "var x : [0..10] init 0;"]
    for i in range(n + 1):
        attrs = " initial" if i == 0 else " final" if i == n else ""
        lines.append(f"mode {name('M', i)} = {i}{attrs};")
    for i in range(n):
        c, f, m, nxt = name("C", i), name("F", i), name("M", i), name("M", i + 1)
        lines += [f"const int {c} = {i % 7} + 1;",
                  f"formula {f} = x + {c};",
                  f"label {name('l', i)} = x == {i % 10} && mode == {m};",
                  f"action {name('A', i)} in {m} when {f} >= 0 {{ goto {nxt}; x := {i % 10}; }}"]
    lines.append(f"property done = P=? [ F mode == {name('M', n)} ];")
    return "\n".join(lines) + "\n"


def long_names(length: int) -> str:
    return declarations(60, pad=length)


def long_expression(n: int) -> str:
    """A guard that sums n terms, 100 to a bracket."""
    groups = []
    for g in range(0, n, 100):
        groups.append("(" + " + ".join("x" if k % 2 else str(k % 3)
                                       for k in range(g, min(n, g + 100))) + ")")
    return ("machine long;\nvar x : [0..3] init 0;\nmode S = 0 initial;\nmode D = 1 final;\n"
            f"formula big = {' + '.join(groups)};\n"
            "action Go in S when big >= 0 { goto D; }\n"
            "property done = P=? [ F mode == D ];\n")


def syntax_error_after_name(n: int) -> str:
    return "machine m;\nconst int " + "a" * n + " = 1; }\n"


def chain(n: int) -> str:
    return "machine m;\nconst int N = " + "+".join(["1"] * n) + ";\n"


def long_number(n: int) -> str:
    return "machine m;\nconst int N = " + "1" * n + ";\n"


def too_large(n: int) -> str:
    return "machine m;\n" + "// padding\n" * (n // 11 + 1)


def _parse(text: str) -> None:
    parser._parse_module.cache_clear()
    parser.parse(text, "bench.afsm")


def _check(text: str) -> None:
    parser._parse_module.cache_clear()
    load("bench.afsm", {}, text=text)


def _fmt(text: str) -> None:
    parser._parse_module.cache_clear()
    format_text(text, "bench.afsm")


STAGES: dict[str, Callable[[str], None]] = {"parse": _parse, "check": _check, "fmt": _fmt}
# shape -> (generator, x1 size, stages, what the size counts)
SHAPES: dict[str, tuple[Callable[[int], str], int, tuple[str, ...], str]] = {
    "declarations": (declarations, 300, ("parse", "check", "fmt"), "modes"),
    "long names": (long_names, 100, ("parse", "check", "fmt"), "characters a name"),
    "long expression": (long_expression, 3000, ("parse", "check", "fmt"), "terms"),
    "syntax error after a long name": (syntax_error_after_name, 40_000, ("check",), "characters"),
    "chain 1+1+... (E113)": (chain, 100_000, ("check",), "terms"),
    "number of n digits (E125)": (long_number, 4301, ("check",), "digits"),
    "file beyond the limit (E004)": (too_large, MAX_SOURCE_CHARS + 1, ("check",), "characters"),
}


# The declarations file of 1 MB (1,019,904 characters): the issue's "a spec of 1 MB is
# answered in under 10 s".
MB_MODES = 6000


def one_megabyte(repeat: int) -> None:
    text = declarations(MB_MODES)
    print("| input | chars | stage | CPU s | answer |")
    print("|---|---:|---|---:|---|")
    for stage in ("parse", "check"):
        t, answer = measure(STAGES[stage], text, repeat)
        print(f"| declarations, {MB_MODES:,} modes | {len(text):,} | {stage} | {t:.2f} | "
              f"{answer} |", flush=True)


def measure(stage: Callable[[str], None], text: str, repeat: int) -> tuple[float, str]:
    """The median CPU time of `stage` on `text`, and what it answered."""
    answer = "ok"
    times = []
    for i in range(repeat + 1):
        t0 = time.process_time()
        try:
            stage(text)
        except CompileError as exc:
            answer = exc.diagnostics[0].code
        if i:  # the first run is a warm-up
            times.append(time.process_time() - t0)
    return statistics.median(times), answer


def _command(argv: list[str]) -> float:
    """CPU seconds (user + system) of `python -m afsmc ARGV` in a child process."""
    before = os.times()
    subprocess.run([sys.executable, "-m", "afsmc", *argv], cwd=ROOT, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, check=False)
    after = os.times()
    return (after.children_user - before.children_user) + (after.children_system
                                                           - before.children_system)


def slope(sizes: list[float], times: list[float]) -> float:
    """The least-squares slope of log(time) against log(size)."""
    xs = [math.log(x) for x in sizes]
    ys = [math.log(max(t, 1e-3)) for t in times]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sum(
        (x - mx) ** 2 for x in xs)


def _guarded(n: int) -> str:
    """examples/overtake.afsm with an n-term sum in Continue's guard."""
    with open(os.path.join(ROOT, "examples", "overtake.afsm"), encoding="utf-8") as f:
        src = f.read()
    key = "action Continue in Pass when "
    return src.replace(key, key + "(" + " + ".join(
        "left" if k % 2 else "clear" for k in range(n)) + ") >= 0 && ")


def _on_file(text: str, argv: Callable[[str, str], list[str]]) -> tuple[float, int]:
    """CPU seconds of the command `argv(path, out dir)` on `text` written to a file, and
    the bytes it wrote to the out dir."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "bench.afsm")
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)
        out = os.path.join(tmp, "out")
        os.mkdir(out)
        t = _command(argv(path, out))
        return t, sum(os.path.getsize(os.path.join(out, x)) for x in os.listdir(out))


def _patrol(cells: int) -> dict[str, float]:
    from benchmarks.patrol_chain import run_one
    out = {}
    for solver in ("topological", "auto"):
        row = run_one(cells, solver, 3600)
        out[solver] = float(str(row["cpu_s"]))
    return out


def _lsp(n: int) -> dict[str, float]:
    from benchmarks.lsp_latency import while_big_document
    text = "machine big;\nmode A = 0 initial final;\n" + "".join(
        f"const int C{i} = {i % 97};\n" for i in range(n))
    got = asyncio.run(while_big_document(text))
    return {k: v for k, v in got.items() if "sent at" not in k}


FOUR: dict[str, tuple[list[int], str, Callable[[int], dict[str, float]]]] = {
    "check": ([750, 1500, 3000, 6000], "modes", lambda n: {
        "CPU s": _on_file(declarations(n), lambda p, o: ["check", p])[0]}),
    "compile (PRISM)": ([750, 1500, 3000, 6000], "modes", lambda n: {
        "CPU s": _on_file(declarations(n), lambda p, o: ["compile", p, "-o", o])[0]}),
    "JANI": ([500, 1000, 2000, 4000], "terms", lambda n: dict(zip(("CPU s", "bytes"), _on_file(
        _guarded(n), lambda p, o: ["compile", "-t", "jani", p, "-o", o]), strict=True))),
    "fmt": ([750, 1500, 3000, 6000], "modes", lambda n: {
        "CPU s": _on_file(declarations(n), lambda p, o: ["fmt", p])[0]}),
    "explorer (patrol)": ([500, 1000, 2000, 4000], "CELLS", _patrol),
    "language server": ([11_250, 22_500, 45_000, 90_000], "constants", _lsp),
}


def four(only: str | None) -> None:
    """The table; the slope counts the commands' start-up (about a second of imports, the
    same at every size), so x8 / x4 (2.0: linear, 4.0: quadratic) says more of the large end."""
    start = _on_file("machine m;\nmode A = 0 initial final;\n", lambda p, o: ["check", p])[0]
    print(f"start-up: `afsmc check` of a two-line file takes {start:.2f} s of CPU\n")
    print("| stage | size | measure | x1 | x2 | x4 | x8 | slope | x8 / x4 |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|")
    for stage, (sizes, unit, run) in FOUR.items():
        if only and only not in stage:
            continue
        got = [run(n) for n in sizes]
        for key in got[0]:
            vals = [g[key] for g in got]
            cells = " | ".join(f"{v:,.0f}" if key == "bytes" else f"{v:.2f}" for v in vals)
            print(f"| {stage} | {sizes[0]:,}-{sizes[-1]:,} {unit} | {key} | {cells} | "
                  f"{slope([float(x) for x in sizes], vals):.2f} | "
                  f"{vals[3] / max(vals[2], 1e-9):.2f} |", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--four", action="store_true", help="each stage at four sizes, and slopes")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scale", type=float, default=1.0, help="multiply the x1 sizes")
    ap.add_argument("--only", help="measure only the shapes whose name contains this")
    ap.add_argument("--mb", action="store_true", help="only check a 1 MB declarations file")
    args = ap.parse_args()
    if args.four:
        four(args.only)
        return 0
    if args.mb:
        one_megabyte(args.repeat)
        return 0
    print("| input | x1 size | x1 chars | x10 chars | stage | x1 s | x10 s | ratio | answer |")
    print("|---|---:|---:|---:|---|---:|---:|---:|---|")
    for shape, (make, size, stages, unit) in SHAPES.items():
        if args.only and args.only not in shape:
            continue
        n = max(1, int(size * args.scale)) if "E004" not in shape else size
        small, large = make(n), make(10 * n)
        for stage in stages:
            t1, a1 = measure(STAGES[stage], small, args.repeat)
            t10, a10 = measure(STAGES[stage], large, args.repeat)
            answer = a1 if a1 == a10 else f"{a1} / {a10}"
            print(f"| {shape} | {n:,} {unit} | {len(small):,} | {len(large):,} | {stage} | "
                  f"{t1:.3f} | {t10:.3f} | {t10 / max(t1, 1e-3):.1f} | {answer} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
