"""`afsmc report`: the page's structure (parsed, never compared as a picture), every
number in it equal to `afsmc verify --json`'s, the same bytes twice but for the stated
timestamp line, nothing fetched and no script, the Markdown form, --baseline, and a
report of every gallery example."""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

from tests.conftest import EXAMPLES, ROOT, run_cli
from tests.specs import patrol_with_requirements

pytestmark = [pytest.mark.storm, pytest.mark.slow]  # full reports: 4-8 s each

SECTIONS = ["mission", "requirements", "what-matters-most", "how-it-fails", "worst-case",
            "figures", "reproducibility"]


class Page(HTMLParser):
    """The parts of a report a test reads: the sections' ids, every table by its class
    (rows of cell texts, the head first), the tags met and the attributes' values."""

    def __init__(self, text: str):
        super().__init__()
        self.sections: list[str] = []
        self.tables: dict[str, list[list[list[str]]]] = {}
        self.tags: list[str] = []
        self.attrs: list[str] = []
        self._row: list[str] | None = None
        self._cell: list[str] | None = None
        self._table: list[list[str]] | None = None
        self.feed(text)

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = dict(attrs)
        self.tags.append(tag)
        # namespace names are no address anything is fetched from
        self.attrs += [v or "" for k, v in attrs if not k.startswith("xmlns")]
        if tag == "section":
            self.sections.append(a.get("id") or "")
        elif tag == "table":
            self._table = []
            self.tables.setdefault(a.get("class") or "", []).append(self._table)
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag: str) -> None:
        if tag in ("td", "th") and self._row is not None and self._cell is not None:
            self._row.append("".join(self._cell))
            self._cell = None
        elif tag == "tr" and self._table is not None and self._row is not None:
            self._table.append(self._row)
            self._row = None

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self._cell.append(data)


@pytest.fixture(scope="module")
def spec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return patrol_with_requirements(tmp_path_factory.mktemp("report"))


@pytest.fixture(scope="module")
def page(spec: Path) -> tuple[str, Page]:
    out = spec.parent / "r.html"
    r = run_cli("report", str(spec), "-o", str(out))
    assert r.code == 0, r.err
    text = out.read_text(encoding="utf-8")
    return text, Page(text)


def _rows(p: Page, cls: str) -> list[dict[str, str]]:
    out = []
    for table in p.tables[cls]:
        head = table[0]
        out += [dict(zip(head, row, strict=True)) for row in table[1:]]
    return out


def test_every_section_is_there_in_order(page: tuple[str, Page]) -> None:
    assert page[1].sections == SECTIONS


def test_it_is_self_contained(page: tuple[str, Page]) -> None:
    text, p = page
    assert "script" not in p.tags and "link" not in p.tags and "img" not in p.tags
    assert "svg" in p.tags and "style" in p.tags
    assert not [a for a in p.attrs if re.match(r"(https?:)?//", a)]
    assert "@import" not in text and "url(" not in text


def test_every_number_equals_verify_json(spec: Path, page: tuple[str, Page]) -> None:
    r = run_cli("verify", str(spec), "--json")
    props = {p["name"]: p for p in json.loads(r.out)["properties"]}
    reqs = _rows(page[1], "requirements")
    assert [row["requirement"] for row in reqs] == ["fault_low", "finish_ok"]
    for row in reqs:
        p = props[row["requirement"]]
        which, value = row["deciding bound"].split()
        assert row["verdict"] == p["verdict"] and which == p["decided_by"]
        assert float(value) == p[which]  # the same double, printed the same way
        assert float(row["± error"]) == p["error"]
        t = p["threshold"]
        assert row["threshold"] == f"{t['op']} {t['bound']}"
        side = 1 if t["op"].startswith(">") else -1
        assert float(row["margin"]) == pytest.approx(side * (p[which] - t["bound"]), abs=1e-15)
    for row in _rows(page[1], "values"):
        p = props[row["property"]]
        lo, hi = (float(x) for x in row["value (min – max)"].split(" – "))
        assert (lo, hi) == (p["min"], p["max"])


def test_the_causes_sum_to_the_value(spec: Path, page: tuple[str, Page]) -> None:
    tables = page[1].tables["causes"]
    assert len(tables) == 4  # fault and fault_low, each under its min's and max's scheduler
    r = run_cli("verify", str(spec), "-p", "fault", "--json")
    (fault,) = json.loads(r.out)["properties"]
    sums = []
    for table in tables:
        rows = table[1:]
        assert rows[-1][0] == "sum"
        parts = [float(row[-1]) for row in rows[:-1]]
        assert float(rows[-1][-1]) == pytest.approx(sum(parts), abs=1e-15)
        sums.append(float(rows[-1][-1]))
    assert sums[0] == pytest.approx(fault["min"], abs=1e-9)
    assert sums[1] == pytest.approx(fault["max"], abs=1e-9)


def test_the_sensitivities_and_the_playbook(page: tuple[str, Page]) -> None:
    rows = _rows(page[1], "sensitivity")
    assert {(r["requirement"], r["figure"]) for r in rows} == {
        (q, f) for q in ("fault_low", "finish_ok") for f in ("P_FAULT", "P_SLIP")}
    assert all(float(r["derivative"]) != 0 for r in rows)
    play = _rows(page[1], "playbook")
    assert {r["constant"] for r in play} == {"MOVE_COST"}
    # the worst case of each requirement and of fault (its max): moving costs 2, always
    assert {r["takes"] for r in play} == {"ceil 2"} and {r["when"] for r in play} == {"always"}
    assert len(page[1].tables["playbook"]) == 3


def test_the_same_bytes_but_for_the_timestamp(spec: Path, page: tuple[str, Page]) -> None:
    again = spec.parent / "again.html"
    assert run_cli("report", str(spec), "-o", str(again)).code == 0
    a, b = page[0].splitlines(), again.read_text(encoding="utf-8").splitlines()
    differ = [(x, y) for x, y in zip(a, b, strict=True) if x != y]
    assert all(x.startswith('<p class="note">Generated ') for x, _ in differ), differ
    reproduce = dict(r for r in page[1].tables["reproduce"][0][1:])
    assert reproduce["command"] == f"afsmc report {spec}"
    assert set(reproduce) >= {"afsmc", "Storm", "Python", f"sha256 {spec}", "model", "engine"}


def test_markdown_has_the_same_sections(spec: Path) -> None:
    r = run_cli("report", str(spec), "--format", "md", "-o", "-", "--no-sensitivity")
    assert r.code == 0, r.err
    heads = re.findall(r"^## (.+)$", r.out, re.M)
    assert heads == ["The mission: patrol", "Requirements", "What matters most",
                     "How it fails", "The worst case", "Where the figures come from",
                     "Reproducibility"]
    assert "Not computed for this report (--no-sensitivity)." in r.out


def test_the_figures_of_the_uav_are_listed_not_rechecked(tmp_path: Path) -> None:
    out = tmp_path / "uav.html"
    r = run_cli("report", str(EXAMPLES / "uav.afsm"), "-o", str(out), "-p", "emergency")
    assert r.code == 0, r.err
    p = Page(out.read_text(encoding="utf-8"))
    rows = _rows(p, "figures")
    assert {row["constant"] for row in rows} >= {"T_TAKEOFF", "P_INIT_FAIL", "P_DROP"}
    assert {row["fresh sim-check"] for row in rows} == {"not re-checked"}
    assert next(r for r in rows if r["constant"] == "P_DROP")["source"] == \
        "sim uav.transport.drop"
    causes = p.tables["causes"]
    assert {row[1] for t in causes for row in t[1:-1]} == {"Emergency"}


def test_report_baseline_flags_a_flip(spec: Path, tmp_path: Path) -> None:
    base = tmp_path / "old.json"
    base.write_text(run_cli("verify", str(spec), "--json").out, encoding="utf-8")
    worse = tmp_path / "worse.afsm"
    worse.write_text(spec.read_text(encoding="utf-8").replace(
        "P_FAULT  = 0.01", "P_FAULT  = 0.02"), encoding="utf-8")
    out = tmp_path / "r.html"
    r = run_cli("report", str(worse), "--baseline", str(base), "-o", str(out),
                "--no-sensitivity")
    assert r.code == 1, r.err
    p = Page(out.read_text(encoding="utf-8"))
    assert "what-changed" in p.sections
    flags = {row["property"]: row["flag"] for row in _rows(p, "changes")}
    assert flags["fault_low"] == "worse" and flags["finish_ok"] == "worse"


GALLERY = sorted(EXAMPLES.glob("*.afsm"))


@pytest.mark.parametrize("path", GALLERY, ids=[p.stem for p in GALLERY])
def test_every_gallery_example_has_a_report(path: Path, tmp_path: Path) -> None:
    args = path.with_suffix(".gallery.args")
    extra = [f"@{args}"] if args.exists() else []
    out = tmp_path / "r.html"
    r = run_cli("report", str(path), *extra, "-o", str(out), "--no-sensitivity")
    assert r.code in (0, 1), r.err  # 1: a requirement of the example does not hold
    p = Page(out.read_text(encoding="utf-8"))
    assert p.sections == SECTIONS and "svg" in p.tags
    assert (ROOT / "docs").is_dir()


def test_the_api_report_is_the_commands(spec: Path, page: tuple[str, Page],
                                        tmp_path: Path) -> None:
    import afsmc

    r = afsmc.load(str(spec)).report()
    inline = Page(r._repr_html_())
    assert inline.sections == SECTIONS and "svg" in inline.tags
    # the same content as the command's page, but for the line that says how it was made
    ours = [x for x in r.html().splitlines() if "Generated" not in x and "Made from" not in x]
    theirs = [x for x in page[0].splitlines() if "Generated" not in x]
    assert ours == theirs
    saved = r.save(tmp_path / "r.md")
    assert Path(saved).read_text(encoding="utf-8").startswith("# Assurance case: patrol")


def test_the_costly_sections_can_be_left_out(spec: Path) -> None:
    r = run_cli("report", str(spec), "-o", "-", "--no-worst-case", "--no-causes",
                "--no-sensitivity")
    assert r.code == 0, r.err
    p = Page(r.out)
    assert p.sections == SECTIONS
    assert "playbook" not in p.tables and "causes" not in p.tables
    for flag in ("--no-worst-case", "--no-causes", "--no-sensitivity"):
        assert f"Not computed for this report ({flag})." in r.out


def test_a_missed_requirement_has_a_negative_margin() -> None:
    r = run_cli("report", str(EXAMPLES / "patrol.afsm"), "-f", 'P>=0.9 [ F "done" ]', "-o",
                "-", "--no-worst-case", "--no-causes", "--no-sensitivity")
    assert r.code == 0, r.err  # the report is made; the verdict is in it
    (row,) = _rows(Page(r.out), "requirements")
    v = json.loads(run_cli("verify", str(EXAMPLES / "patrol.afsm"), "-f",
                           'P>=0.9 [ F "done" ]', "--json").out)["properties"][0]
    assert row["verdict"] == v["verdict"] == "fails" and v["decided_by"] == "max"
    assert float(row["margin"]) == pytest.approx(v["max"] - 0.9, abs=1e-15)
    assert float(row["margin"]) < 0


def test_the_likeliest_paths_into_the_largest_cause(page: tuple[str, Page]) -> None:
    tables = page[1].tables["paths"]
    assert len(tables) == 2  # fault's and fault_low's, under their max's scheduler
    rows = tables[0][1:]
    assert len(rows) == 3
    probs = [float(r[1]) for r in rows]
    assert probs == sorted(probs, reverse=True)
    # the likeliest: a fault in the first move (P_FAULT); then one good move first
    assert probs[0] == pytest.approx(0.01, rel=1e-12)
    assert probs[1] == pytest.approx(0.99 * 0.9 * 0.01, rel=1e-12)
    assert all(r[2].endswith("Patrol: Fault in Move → Halted") for r in rows)


def test_recheck_gives_sim_checks_verdicts(tmp_path: Path) -> None:
    import afsmc

    out = tmp_path / "r.html"
    r = run_cli("report", str(EXAMPLES / "uav.afsm"), "-p", "emergency", "--no-worst-case",
                "--no-causes", "--recheck", "200", "-o", str(out))
    assert r.code == 0, r.err
    rows = {row["constant"]: row["fresh sim-check"]
            for row in _rows(Page(out.read_text(encoding="utf-8")), "figures")}
    check = afsmc.load(str(EXAMPLES / "uav.afsm")).sim_check(runs=200)
    assert set(rows) == {e.name for e in check.evidence}
    for e in check.evidence:  # the same seed: the same verdicts
        assert rows[e.name].startswith(f"{e.verdict}: mean ") and "over 200 runs" in rows[e.name]
