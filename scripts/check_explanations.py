"""Check the explanations of the diagnostic codes, afsmc/diagnostics/explanations/<CODE>.md.

Each file reads

    # E301: weights of enabled actions tie

    Prose.

    ## Wrong

    ```afsm
    ... a complete file that triggers the code ...
    ```

    ## Right

    ```afsm
    ... the same file fixed ...
    ```

Codes that `afsmc check` cannot show have ```sh blocks with the command lines that provoke
them (and may keep an ```afsm block: the file the commands name).

What is checked:
- the title line names the file's code, starts in lower case and ends without a period;
- both sections are there, each with a block;
- a section with only an ```afsm block is checked in-process as `afsmc check` would: Wrong
  must report the code, Right must report no error and not the code;
- with --run-sh, a section with ```sh blocks runs them with bash in a fresh directory
  where its ```afsm block is saved under the first *.afsm name the commands use (default
  m.afsm) and `afsmc` is this worktree's afsmc: Wrong's output must show the code, Right's
  must show no error and not the code. Codes listed in NOT_RUNNABLE describe conditions a
  command line cannot set up (a crash, a full disk, a killed process) and are not run.

Usage: python scripts/check_explanations.py [--run-sh] [CODE ...]
Exit 1 if any check fails.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from afsmc.diagnostics.explain import Explanation, Section  # noqa: E402
from afsmc.diagnostics.explain import parse as parse_text  # noqa: E402

EXPLANATIONS = ROOT / "afsmc" / "diagnostics" / "explanations"

# Conditions no command line sets up reliably: internal errors, resources, third parties.
NOT_RUNNABLE = frozenset({
    "E009", "E190", "E402", "E406", "E408", "E411", "E414", "E505", "E506", "E612",
    "E999", "N412",
})

def parse(path: Path) -> Explanation:
    """The file as afsmc reads it (afsmc.diagnostics.explain: one parser for both)."""
    return parse_text(path.read_text(encoding="utf-8"))


def codes_of_check(text: str, consts: dict[str, str] | None = None) -> list[tuple[str, str]]:
    """(code, severity) of every diagnostic `afsmc check` reports on `text`."""
    from afsmc.compiler import load
    from afsmc.diagnostics import CompileError

    try:
        diags = load("m.afsm", consts or {}, text=text).diagnostics
    except CompileError as exc:
        diags = list(exc.diagnostics)
    return [(d.code, str(d.severity)) for d in diags]


def _shim(directory: Path) -> Path:
    """A bin directory whose `afsmc` runs this worktree's afsmc with this Python."""
    bin_dir = directory / "bin"
    bin_dir.mkdir()
    exe = bin_dir / "afsmc"
    exe.write_text(f"#!/bin/sh\nPYTHONPATH={shlex.quote(str(ROOT))} exec "
                   f"{shlex.quote(sys.executable)} -m afsmc \"$@\"\n", encoding="utf-8")
    exe.chmod(0o755)
    return bin_dir


def run_sh(section: Section, timeout: float) -> str:
    """Run the section's sh blocks in a fresh directory; their stdout and stderr."""
    script = "\n".join(section.of("sh"))
    names = re.findall(r"[\w.-]+\.afsm\b", script) or ["m.afsm"]
    with tempfile.TemporaryDirectory(prefix="afsmc-explain-") as tmp:
        work = Path(tmp)
        for text in section.of("afsm"):
            (work / names[0]).write_text(text, encoding="utf-8")
        env = dict(os.environ, PATH=f"{_shim(work)}{os.pathsep}{os.environ.get('PATH', '')}",
                   NO_COLOR="1")
        try:
            done = subprocess.run(["bash", "-c", script], cwd=work, env=env, text=True,
                                  capture_output=True, timeout=timeout, check=False)
        except subprocess.TimeoutExpired as exc:
            said = [x.decode() if isinstance(x, bytes) else x or "" for x in (exc.stdout, exc.stderr)]
            return f"(timed out after {timeout:.0f} s)\n" + "".join(said)
        return done.stdout + done.stderr


def _shows(output: str, code: str) -> bool:
    return f"[{code}]" in output or f'"code": "{code}"' in output


def _has_error(output: str) -> bool:
    return "error[" in output or '"severity": "error"' in output


def check(path: Path, run_shell: bool, timeout: float) -> tuple[str, list[str], list[str]]:
    """('ok' | 'fail' | 'skipped', problems, notes) of one explanation."""
    problems: list[str] = []
    notes: list[str] = []
    try:
        ex = parse(path)
    except ValueError as exc:
        return "fail", [str(exc)], notes
    if ex.code != path.stem:
        problems.append(f"the title names {ex.code}, the file {path.stem}")
    if ex.title[0].isupper() or ex.title.endswith("."):
        problems.append(f"the title should start in lower case and end without '.': {ex.title!r}")
    if not ex.prose:
        problems.append("no prose before '## Wrong'")
    for name, sec in (("Wrong", ex.wrong), ("Right", ex.right)):
        if not sec.blocks:
            problems.append(f"'## {name}' has no code block")
    if problems:
        return "fail", problems, notes
    code = ex.code
    if not ex.wrong.of("sh") and not ex.right.of("sh"):
        wrong, right = ex.wrong.of("afsm"), ex.right.of("afsm")
        if len(wrong) != 1 or len(right) != 1:
            return "fail", ["expected one ```afsm block in each section"], notes
        got = codes_of_check(wrong[0])
        if code not in {c for c, _ in got}:
            problems.append(f"Wrong does not report {code}: {got or 'nothing'}")
        elif others := sorted({c for c, _ in got} - {code}):
            notes.append(f"Wrong also reports {', '.join(others)}")
        got = codes_of_check(right[0])
        if code in {c for c, _ in got}:
            problems.append(f"Right still reports {code}")
        if errors := sorted({c for c, s in got if s == "error"}):
            problems.append(f"Right reports errors: {', '.join(errors)}")
        elif got:
            notes.append(f"Right reports {', '.join(sorted({c for c, _ in got}))}")
        return ("fail" if problems else "ok"), problems, notes
    if not run_shell or code in NOT_RUNNABLE:
        return "skipped", problems, notes
    out = run_sh(ex.wrong, timeout)
    if not _shows(out, code):
        problems.append(f"Wrong's commands do not show {code}:\n{out.strip()[-800:]}")
    out = run_sh(ex.right, timeout)
    if _shows(out, code) or _has_error(out):
        problems.append(f"Right's commands show {code} or an error:\n{out.strip()[-800:]}")
    return ("fail" if problems else "ok"), problems, notes


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("codes", nargs="*", help="codes to check (default: every file)")
    ap.add_argument("--run-sh", action="store_true", help="also run the ```sh examples")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per sh section")
    ap.add_argument("-v", "--verbose", action="store_true", help="print the notes too")
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    paths = sorted(EXPLANATIONS.glob("*.md"))
    if args.codes:
        paths = [p for p in paths if p.stem in args.codes]
    counts = {"ok": 0, "fail": 0, "skipped": 0}
    for path in paths:
        status, problems, notes = check(path, args.run_sh, args.timeout)
        counts[status] += 1
        if status != "ok" or (args.verbose and notes):
            print(f"{path.stem}: {status}")
        for p in problems:
            print(f"  - {p}")
        if args.verbose:
            for n in notes:
                print(f"  . {n}")
    print(f"{len(paths)} explanations: {counts['ok']} ok, {counts['fail']} failed, "
          f"{counts['skipped']} skipped (sh examples"
          + ("" if args.run_sh else "; --run-sh runs them") + ")")
    return 1 if counts["fail"] else 0


if __name__ == "__main__":
    sys.exit(main())
