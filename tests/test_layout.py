"""The layout holds: layers and no cycles (import-linter), small files, a short top level,
and the viewer in the base install."""

import re
import shutil
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

import rtta

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("rtta", "viewer", "tests", "scripts", "shaders")
MAX_LINES = 400


def _lint_imports() -> str | None:
    found = shutil.which("lint-imports") or str(Path(sys.executable).with_name("lint-imports"))
    return found if Path(found).exists() else None


def test_import_contracts_are_kept():
    """The layers, the library-never-imports-the-viewer and the no-cycle contracts of pyproject.toml."""
    exe = _lint_imports()
    if exe is None:
        pytest.fail("lint-imports is not installed (it is in the test extra)")
    run = subprocess.run([exe, "--no-cache"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    kept = re.findall(r"^(.*) KEPT$", run.stdout, re.MULTILINE)
    assert len(kept) >= 4, run.stdout  # rtta layers, forbidden viewer, viewer layers, acyclic


def test_no_file_over_400_lines():
    long = []
    for folder in SOURCES:
        for path in (ROOT / folder).rglob("*"):
            if path.is_file() and path.suffix in {".py", ".glsl", ".vert", ".frag", ".geom", ".comp", ".sh"}:
                n = len(path.read_text(encoding="utf-8").splitlines())
                if n > MAX_LINES:
                    long.append(f"{path.relative_to(ROOT)}: {n}")
    assert not long, long


def test_the_top_of_rtta_stays_short():
    entries = [p.name for p in (ROOT / "rtta").iterdir() if p.name != "__pycache__"]
    assert len(entries) <= 14, sorted(entries)  # the layers, and errors, outputs, memory
    for package in ("scene", "atlas", "gl", "passes", "ldi", "renderer", "dataset", "bench", "cli"):
        doc = (ROOT / "rtta" / package / "__init__.py").read_text(encoding="utf-8")
        said = doc.split('"""')[1].lower()
        assert doc.startswith('"""') and "import" in said, f"rtta/{package}: say what it may import"


def test_public_face_is_small_and_resolves():
    assert 10 <= len(rtta.__all__) <= 30
    for name in rtta.__all__:
        assert getattr(rtta, name) is not None, name


def test_viewer_is_in_the_base_install():
    """`pip install rtta` gives a working `rtta-view`: its packages are dependencies, not an extra."""
    requires = metadata.requires("rtta") or []
    base = {re.split(r"[<>=!~ \[;]", r, maxsplit=1)[0].lower() for r in requires if "extra ==" not in r}
    assert {"moderngl-window", "pyglet", "imgui-bundle"} <= base, sorted(base)
    scripts = {
        ep.name: ep.value
        for ep in metadata.entry_points(group="console_scripts")
        if ep.dist is not None and ep.dist.name == "rtta"
    }
    assert scripts.get("rtta-view") == "viewer:cli" and scripts.get("rtta") == "rtta.cli.main:main"
    import imgui_bundle  # noqa: F401  (installed with rtta itself)
    import moderngl_window  # noqa: F401


def test_every_package_is_installed():
    """pyproject.toml lists the packages setuptools installs: a new one left out is missing from
    the wheel and CI's install (rtta.outputs was, when it became a package)."""
    import tomllib

    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]["packages"])
    found = {
        ".".join(init.parent.relative_to(ROOT).parts)
        for top in ("rtta", "viewer")
        for init in (ROOT / top).rglob("__init__.py")
        if "__pycache__" not in init.parts
    }
    assert found <= listed, sorted(found - listed)
