"""The docs hold: the site builds with `mkdocs build --strict` (a broken link, anchor or API
reference fails it), every Python block of README.md and docs/ runs as written, the README is
short and starts with the two commands, and every name `import rtta` exports is documented."""

from __future__ import annotations

import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import rtta

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)
NOT_RUN = re.compile(r"<!--\s*not run:\s*(\S[^>]*?)\s*-->\s*$")
EXAMPLE = re.compile(r'--8<-- "(examples/\w+\.py)"')  # a script included whole: tests/test_examples.py runs it
TWO_COMMANDS = ["bash scripts/run.sh", "bash scripts/test.sh"]


def code_blocks(text: str) -> list[tuple[int, str, str, str | None]]:
    """(line, language, code, reason it is not run or None) of every fenced block."""
    blocks = []
    for m in FENCE.finditer(text):
        before = text[: m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        skip = NOT_RUN.search(before)
        blocks.append((text.count("\n", 0, m.start()) + 1, m.group(1), m.group(2), skip and skip.group(1)))
    return blocks


def _python_blocks() -> list:
    found = []
    for page in PAGES:
        for line, lang, code, skip in code_blocks(page.read_text(encoding="utf-8")):
            if lang in ("python", "py") and EXAMPLE.fullmatch(code.strip()):
                assert (ROOT / EXAMPLE.fullmatch(code.strip()).group(1)).is_file(), code  # run by test_examples
                continue
            if lang in ("python", "py"):
                name = f"{page.relative_to(ROOT)}:{line}"
                marks = [pytest.mark.skip(reason=f"marked <!-- not run: {skip} -->")] if skip else []
                found.append(pytest.param(code, id=name, marks=marks))
    return found


def test_block_parser_sees_fences_and_marks():
    text = "x\n```sh\nls\n```\n<!-- not run: needs a cluster -->\n```python\nimport rtta\n```\n```python\n1\n```\n"
    blocks = code_blocks(text)
    expected = [(2, "sh", None), (6, "python", "needs a cluster"), (9, "python", None)]
    assert [(b[0], b[1], b[3]) for b in blocks] == expected
    assert blocks[1][2] == "import rtta\n"


def test_the_site_builds_strictly(tmp_path):
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(ROOT / "mkdocs.yml"), "-d", str(tmp_path)]
    run = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=180, env=env)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-6000:]
    api = (tmp_path / "api" / "index.html").read_text(encoding="utf-8")
    for name in rtta.__all__:  # the reference covers the public face
        assert f'id="rtta.{name}"' in api, name


@pytest.mark.parametrize("code", _python_blocks())
def test_python_block_runs(code, tmp_path):
    """Each block in a fresh process, in an empty folder: it makes its own headless context."""
    script = tmp_path / "block.py"
    script.write_text(code, encoding="utf-8")
    run = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-4000:]


def test_the_docs_have_python_blocks_that_run():
    params = _python_blocks()
    run = [p for p in params if not p.marks]
    assert len(run) >= 3 and len(run) > 2 * (len(params) - len(run)), [p.id for p in params]
    assert any(p.id.startswith("README.md:") for p in run)


def test_readme_is_short_and_starts_with_the_two_commands():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 200
    line, lang, code, _ = code_blocks(text)[0]
    commands = [row.split("#")[0].strip() for row in code.splitlines() if row.split("#")[0].strip()]
    assert lang in ("sh", "bash", "") and commands == TWO_COMMANDS, code
    assert text.startswith("# ") and "![" in text[: text.index("```")]  # title and a picture first
    for script in ("run.sh", "test.sh"):
        assert (ROOT / "scripts" / script).is_file()


def test_every_public_name_has_a_numpy_docstring():
    assert "Style" in rtta.__all__
    missing, sections = [], []
    for name in rtta.__all__:
        obj = getattr(rtta, name)
        doc = inspect.getdoc(obj) or ""
        if not doc.strip() or doc.startswith(f"{name}("):  # none, or the dataclass's generated one
            missing.append(name)
            continue
        summary = doc.strip().split("\n\n")[0]
        if not summary.rstrip().endswith("."):
            sections.append(f"{name}: the summary should be a sentence")
        if inspect.isfunction(obj):
            wanted = ("Parameters",) if inspect.signature(obj).parameters else ("Returns",)
        elif inspect.isclass(obj) and not issubclass(obj, BaseException):
            wanted = ("Parameters", "Attributes")
        else:
            wanted = ()
        if wanted and not any(re.search(rf"^{w}\n-{{3,}}$", doc, re.M) for w in wanted):
            sections.append(f"{name}: no {' or '.join(wanted)} section")
    assert not missing, f"no docstring: {missing}"
    assert not sections, sections
