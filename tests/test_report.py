"""`rtta bench report --quick`: runs headless, writes every section as parseable tables that
name renderer, CPU, date and command, draws the plots, and keeps the rest of the file."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from rtta.bench.report import BEGIN, DEFAULT_MARKDOWN, END, NEW_PAGE, SECTIONS, write_block
from rtta.cli.main import main


def _tables(text: str) -> list[list[list[str]]]:
    """Markdown tables as lists of rows of cells (header first, separator dropped)."""
    tables, current = [], []
    for line in text.splitlines() + [""]:
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if not all(re.fullmatch(r"-+", c) for c in cells):
                current.append(cells)
        elif current:
            tables.append(current)
            current = []
    return tables


def _number(cell: str) -> float:
    return float(cell.rstrip("%"))


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory, ctx):
    folder = tmp_path_factory.mktemp("report")
    md = folder / "BENCH.md"
    md.write_text("# Benchmarks\n\nhand-written text that must stay\n")
    assert main(["bench", "report", "--quick", "--markdown", str(md), "--plots", str(folder / "plots")]) == 0
    assert ctx.error == "GL_NO_ERROR"
    return md, folder / "plots"


def test_every_section_has_stamped_tables(quick_report, ctx):
    md, _ = quick_report
    text = md.read_text()
    assert text.startswith("# Benchmarks\n\nhand-written text that must stay\n")
    block = text[text.index(BEGIN) : text.index(END)]
    chunks = re.split(r"^### ", block, flags=re.M)[1:]
    assert [c.splitlines()[0] for c in chunks] == list(SECTIONS)
    for chunk in chunks[:5]:
        assert ctx.info["GL_RENDERER"] in chunk and "CPU " in chunk and "command `rtta bench report --quick`" in chunk
        assert re.search(r"\d{4}-\d\d-\d\d", chunk)
        (tbl, *more) = _tables(chunk)
        header, rows = tbl[0], tbl[1:]
        assert rows and all(len(r) == len(header) for r in rows)
        for extra in more:
            assert len(extra) > 1 and all(len(r) == len(extra[0]) for r in extra)


def test_numbers_parse_and_are_plausible(quick_report):
    text = quick_report[0].read_text()
    tables = _tables(text)
    error = next(t for t in tables if t[0][:3] == ["scene", "scale", "border"])
    col = {name: i for i, name in enumerate(error[0])}
    for row in error[1:]:
        assert _number(row[col["frame ms"]]) > 0
        off = _number(row[col["pixels off > 3/255"]])
        assert 0 <= off <= 100
        if float(row[col["scale"]]) == 1.0:  # at scale 1 sprites reconstruct STD
            assert off < 0.5 and int(row[col["holes"]]) == 0
    capture = next(t for t in tables if t[0][:2] == ["sweep", "objects"])
    assert all(_number(c) > 0 for r in capture[1:] for c in r[3:7])
    stability = next(t for t in tables if t[0][:2] == ["sweep", "value"])
    assert {r[0] for r in stability[1:]} == {"near/far", "offset", "size ratio"}
    assert all(r[5] == r[6] == r[7] == "0" for r in stability[1:])  # no NaN, holes or GL errors
    ldi = next(t for t in tables if t[0][:2] == ["mesh", "N"])
    assert all(0 <= float(r[4]) < 0.05 for r in ldi[1:])


def test_plots_are_drawn(quick_report):
    _, plots = quick_report
    names = sorted(p.name for p in plots.glob("*.png"))
    assert names == ["capture.png", "error_vs_time.png", "importance.png", "ldi.png", "packing.png", "stability.png"]
    for name in names:
        img = np.asarray(Image.open(plots / name).convert("L"))
        assert img.shape[0] > 300 and img.shape[1] > 600 and img.std() > 10  # not blank
    assert "](plots/error_vs_time.png)" in quick_report[0].read_text()


def test_a_second_run_replaces_the_block(tmp_path, quick_report):
    md = tmp_path / "B.md"
    md.write_text(quick_report[0].read_text() + "\ntail text\n")
    write_block(md, "new block")
    text = md.read_text()
    assert text.count(BEGIN) == 1 and "new block" in text and "### 1." not in text and "tail text" in text


def test_half_a_marker_is_refused_untouched(tmp_path, capsys):
    md = tmp_path / "B.md"
    md.write_text(f"# x\n{BEGIN}\nno end\n")
    assert main(["bench", "report", "--quick", "--markdown", str(md), "--plots", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "B.md" in err[0] and "marker" in err[0]
    assert md.read_text() == f"# x\n{BEGIN}\nno end\n"


def test_importance_section(quick_report):
    """Section 7: each mode's reference row has no error, the defaults are marked, and
    context scale 0.5 changes ghosted-ao (the axis measures something)."""
    text = quick_report[0].read_text()
    section = text.split("### 7.")[1]
    rows = [
        [c.strip() for c in line.strip("|").split("|")]
        for line in section.splitlines()
        if line.startswith("| ") and not line.startswith("| scene")
    ]
    assert len(rows) == 2 * 8
    first = {}
    for r in rows:
        first.setdefault((r[0], r[1]), r)
    assert all(r[7] == "0.000%" and r[8] == "0.00" for r in first.values())
    assert sum(r[9] == "**yes**" for r in rows) == 2 * 3  # ghosted, ghosted-ao, transparent
    half = [r for r in rows if r[1] == "ghosted-ao" and r[2] == "0.5"]
    assert half and all(float(r[8]) > 0 for r in half)


def test_the_default_target_is_the_docs_report_page(tmp_path):
    """`rtta bench report` writes into the docs site's page, which holds one block; a page that
    does not exist yet is started with a title of its own."""
    page = Path(__file__).resolve().parents[1] / DEFAULT_MARKDOWN
    assert DEFAULT_MARKDOWN.as_posix() == "docs/performance/report.md"
    text = page.read_text()
    assert text.count(BEGIN) == 1 and text.count(END) == 1 and text.index(BEGIN) < text.index(END)
    fresh = tmp_path / "report.md"
    write_block(fresh, "### 1. x")
    assert fresh.read_text() == f"{NEW_PAGE}{BEGIN}\n### 1. x\n{END}\n"
