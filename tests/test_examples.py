"""Every script in examples/ runs (in a subprocess, into a temporary folder) and draws what it
says: a picture that is not blank, plus what that example is about (hidden parts' amodal masks
non-empty, ghosted differs from std, the IFC classes found, the dataset's hidden parts
annotated...). The gallery page is the scripts' own text and source (examples/make_gallery.py)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
import make_gallery  # noqa: E402

OUTLINE = (255, 191, 25)  # the focus outline of the ghosted modes (Style.outline_color)


def _run(name: str, out: Path) -> tuple[np.ndarray, str]:
    done = subprocess.run(
        [sys.executable, str(ROOT / "examples" / f"{name}.py"), str(out)],
        cwd=out,
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    picture = np.asarray(Image.open(out / f"{name}.png").convert("RGB")).astype(int)
    return picture, done.stdout


def _not_blank(picture: np.ndarray) -> None:
    flat = picture.reshape(-1, 3)
    colours, counts = np.unique(flat, axis=0, return_counts=True)
    assert len(colours) > 200, f"only {len(colours)} colours"
    assert 1 - counts.max() / len(flat) > 0.15, "the background covers nearly all of it"


def _near(picture: np.ndarray, colour, tol: int = 3) -> np.ndarray:
    return np.abs(picture - np.array(colour)).max(axis=-1) <= tol


def test_every_script_is_in_the_gallery():
    scripts = sorted(p.stem for p in (ROOT / "examples").glob("*.py") if p.stem != "make_gallery")
    assert sorted(make_gallery.EXAMPLES) == scripts
    for name in scripts:
        assert len((ROOT / "examples" / f"{name}.py").read_text().splitlines()) <= 75, name


def test_the_gallery_page_is_made_from_the_scripts():
    """docs/examples.md is what make_gallery writes now, it shows the scripts themselves
    (included from examples/, no copies), and its pictures are there and small."""
    assert (ROOT / "docs" / "examples.md").read_text(encoding="utf-8") == make_gallery.page()
    for name in make_gallery.EXAMPLES:
        assert f'--8<-- "examples/{name}.py"' in make_gallery.page(), name  # the script itself, not a copy
        assert not (ROOT / "docs" / "examples" / f"{name}.py").exists(), f"{name}.py: a copy under docs/"
        picture = ROOT / "docs" / "examples" / f"{name}.png"
        assert picture.stat().st_size <= make_gallery.MAX_BYTES, name


@pytest.mark.parametrize("name", make_gallery.EXAMPLES)
def test_example_draws_what_it_says(name, tmp_path):
    picture, stdout = _run(name, tmp_path)
    _not_blank(picture)
    CHECKS[name](picture, stdout, tmp_path)


def _demo_modes(picture, stdout, out):
    assert picture.shape == (480, 960, 3)
    tiles = [picture[r * 240 : (r + 1) * 240, c * 320 : (c + 1) * 320] for r in (0, 1) for c in (0, 1, 2)]
    std, ghosted = tiles[0], tiles[3]
    assert (np.abs(ghosted - std).max(axis=2) > 30).mean() > 0.1  # the ghosted view is not the plain one
    blue = [int((t[..., 2] > t[..., 0] + 60).sum()) for t in tiles]  # the hidden pads, shown
    assert blue[0] == 0 and min(blue[3:]) > 500, blue
    assert _near(tiles[3], OUTLINE).sum() > 100  # the focus outlines


def _amodal_masks(picture, stdout, out):
    rows = re.findall(r"^(\w+): visible (\d+) px, amodal (\d+) px$", stdout, re.M)
    assert len(rows) == 4, stdout
    assert all(int(seen) == 0 and int(amodal) > 300 for _, seen, amodal in rows), rows  # hidden, yet whole
    right = picture[:, 480:]
    assert _near(right, (255, 60, 200), 0).sum() > 50  # piston_2's outline drawn
    assert _near(picture[:, :480], (255, 60, 200), 0).sum() == 0


def _atlas_layers(picture, stdout, out):
    count, layers = (int(v) for v in re.search(r"^(\d+) objects in (\d+) layer", stdout, re.M).groups())
    assert count == 24 and layers >= 1
    assert _near(picture, (255, 190, 40), 0).sum() > 24 * 40  # every region outlined


def _own_context(picture, stdout, out):
    assert re.search(r"^12 frames, [\d.]+ ms a frame", stdout, re.M), stdout
    assert picture.shape == (360, 480, 3) and _near(picture, OUTLINE).sum() > 100


def _from_meshes(picture, stdout, out):
    ball = (picture[..., 2] > picture[..., 0] + 60).sum()  # the blue ball inside the housing
    assert ball > 1000 and _near(picture, OUTLINE).sum() > 100


def _gltf_tree(picture, stdout, out):
    assert "arm/wrist/finger_2" in stdout.splitlines() and (out / "arm.glb").is_file()
    left, right = picture[:, :360], picture[:, 360:]
    assert (np.abs(left - right).max(axis=2) > 30).mean() > 0.05
    assert _near(right, OUTLINE).sum() > 50 and _near(left, OUTLINE).sum() == 0  # focus only on the right


def _ifc_by_class(picture, stdout, out):
    names = stdout.splitlines()
    assert sum(n.endswith("IfcWall 'Wall 1'") for n in names) == 1
    assert sum("/IfcWindow '" in n for n in names) == 2 and sum("/IfcDoor '" in n for n in names) == 1
    assert not any("IfcOpeningElement" in n for n in names)  # openings are voids, not objects
    assert _near(picture, OUTLINE).sum() > 200  # the door and windows outlined


def _dask_dataset(picture, stdout, out):
    coco = json.loads((out / "dataset" / "annotations.json").read_text())
    assert len(coco["images"]) == 4 and picture.shape == (480, 640, 3)
    hidden = [a for a in coco["annotations"] if a["area"] == 0 and a["amodal_area"] > 0]
    assert hidden, "no part hidden in any view has its amodal mask"


CHECKS = {
    "demo_modes": _demo_modes,
    "amodal_masks": _amodal_masks,
    "atlas_layers": _atlas_layers,
    "own_context": _own_context,
    "from_meshes": _from_meshes,
    "gltf_tree": _gltf_tree,
    "ifc_by_class": _ifc_by_class,
    "dask_dataset": _dask_dataset,
}
