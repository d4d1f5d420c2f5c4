"""Regenerate the gallery: run every example, then write its picture, small, into
docs/examples/, and the page docs/examples.md (title and text from each
script's docstring, the picture, a link to the script).

    python examples/make_gallery.py              # the pictures and the page
    python examples/make_gallery.py --page-only  # the page alone (after editing a script's text)
"""

import argparse
import ast
import subprocess
import sys
import tempfile
from pathlib import Path

from PIL import Image

HERE = Path(__file__).resolve().parent
DOCS = HERE.parent / "docs"
# gallery order; each script writes OUT_DIR/<name>.png
EXAMPLES = [
    "demo_modes",
    "amodal_masks",
    "atlas_layers",
    "own_context",
    "from_meshes",
    "gltf_tree",
    "ifc_by_class",
    "dask_dataset",
]
MAX_BYTES = 100_000  # per picture in docs/examples/
INTRO = """# Examples

Short scripts in `examples/` (at the top of the repository) that each write one picture with the
library's public API (`import rtta`). Run one with `python examples/NAME.py [OUT_DIR]`
(default `out/examples/`). `python examples/make_gallery.py` regenerates this page, its
pictures and the scripts shown here (included from examples/); `tests/test_examples.py` runs every
script and checks what it draws.
"""


def parts(name: str) -> tuple[str, str, str]:
    """(title, text, usage) of an example from its docstring: the first line, the rest, and
    the usage line (`python examples/NAME.py ...`)."""
    doc = ast.get_docstring(ast.parse((HERE / f"{name}.py").read_text(encoding="utf-8"))) or name
    title, _, rest = doc.partition("\n")
    lines = rest.strip().splitlines()
    usage = [line.strip() for line in lines if line.startswith("    python ")]
    text = "\n".join(line for line in lines if not line.startswith("    python "))
    return title.strip().rstrip("."), text.strip(), usage[0] if usage else f"python examples/{name}.py"


def page() -> str:
    """docs/examples.md, made from the scripts."""
    out = [INTRO]
    for name in EXAMPLES:
        title, text, usage = parts(name)
        out.append(f"## {title}\n\n![{title}](examples/{name}.png)\n\n{text}\n")
        out.append(f'```sh\n{usage}\n```\n\n```python\n--8<-- "examples/{name}.py"\n```\n')
    return "\n".join(out)


def small_png(src: Path, dst: Path) -> int:
    """The picture as RGB, or with an adaptive palette of fewer colours until it fits MAX_BYTES; its size."""
    image = Image.open(src).convert("RGB")
    image.save(dst, optimize=True)
    for colours in (256, 128, 64, 32):
        if dst.stat().st_size <= MAX_BYTES:
            break
        image.quantize(colours, dither=Image.Dither.NONE).save(dst, optimize=True)
    return dst.stat().st_size


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--page-only", action="store_true", help="docs/examples.md only")
    args = parser.parse_args()
    if not args.page_only:
        (DOCS / "examples").mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            for name in EXAMPLES:
                subprocess.run([sys.executable, str(HERE / f"{name}.py"), tmp], check=True, stdout=subprocess.DEVNULL)
                size = small_png(Path(tmp) / f"{name}.png", DOCS / "examples" / f"{name}.png")
                print(f"docs/examples/{name}.png: {size / 1e3:.0f} KB")
    (DOCS / "examples.md").write_text(page(), encoding="utf-8")
    print("wrote docs/examples.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
