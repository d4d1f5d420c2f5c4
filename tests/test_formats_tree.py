"""COLLADA (pycollada), USD (usd-core) and 3DXML (trimesh) files with a nested tree, written
by the tests: the tree, names, units and up axis are kept, USD instances appear, and bad
files (truncated, corrupt, hostile references) are refused in one line."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest
from assemblies import TREE_PARTS, write_3dxml, write_collada, write_usd, write_zae

from rtta.cli.main import main
from rtta.errors import RttaError
from rtta.scene.loader import load_scene
from rtta.scene.select import resolve_names

WRITERS = {
    ".dae": (write_collada, "cm"),
    ".zae": (write_zae, "cm"),
    ".usda": (write_usd, "cm"),
    ".usdc": (write_usd, "cm"),
    ".3dxml": (write_3dxml, "mm"),
}


@pytest.mark.parametrize("suffix", list(WRITERS))
def test_nested_tree_names_units(tmp_path, suffix):
    write, unit = WRITERS[suffix]
    path = tmp_path / f"plant{suffix}"
    write(path)
    s = load_scene(path)
    assert sorted(s.names) == sorted(TREE_PARTS) and s.unit == unit and s.up_axis == "z"
    for name, (groups, t, size) in TREE_PARTS.items():
        oid = s.index(name)
        assert s.path_of(oid) == groups, name
        np.testing.assert_allclose(s.aabb_min[oid], t, atol=1e-4)
        np.testing.assert_allclose(s.aabb_max[oid], np.add(t, size), atol=1e-4)
    assert sorted(s.groups) == ["plant", "plant/arm", "plant/arm/hand"]
    hand = [s.index("finger"), s.index("finger_2")]
    assert resolve_names(s, ["hand"], "--focus") == sorted(hand) == resolve_names(s, ["arm/hand/*"], "--focus")


def test_usd_instances_and_meters_per_unit(tmp_path):
    from pxr import Usd, UsdUtils

    path = tmp_path / "plant.usda"
    write_usd(path)
    stage = Usd.Stage.Open(str(path))
    assert stage.GetPrimAtPath("/plant/arm/hand/finger").IsInstance()  # written as instances
    s = load_scene(path)
    fingers = [s.index("finger"), s.index("finger_2")]
    assert np.allclose(s.aabb_max[fingers[1]] - s.aabb_max[fingers[0]], [14, 0, 0])
    from rtta.scene.readers import usd

    asm = usd.read(path)  # the prototype's mesh is read once for both instances
    a, b = (i for i, n in enumerate(asm.names) if n.startswith("finger"))
    assert np.shares_memory(asm.faces[a], asm.faces[b]) and asm.colors[a] == asm.colors[b]
    assert not np.shares_memory(asm.vertices[a], asm.vertices[b])  # each placed by its own transform
    package = tmp_path / "plant.usdz"
    assert UsdUtils.CreateNewUsdzPackage(str(path), str(package))
    z = load_scene(package)
    assert sorted(z.names) == sorted(s.names) and z.unit == "cm"


def _bad_cases(tmp_path):
    write_collada(tmp_path / "ok.dae")
    dae = (tmp_path / "ok.dae").read_bytes()
    write_usd(tmp_path / "ok.usdc")
    usdc = (tmp_path / "ok.usdc").read_bytes()
    outside = tmp_path.parent / "elsewhere.usda"
    outside.write_text("#usda 1.0\n")
    hostile = zipfile.ZipFile(tmp_path / "hostile.3dxml", "w")
    hostile.writestr("../../evil.xml", "<a/>")
    hostile.close()
    future = bytearray((tmp_path / "hostile.3dxml").read_bytes())
    entry = future.index(b"PK\x01\x02")  # central directory: version needed to extract 10.6
    future[entry + 6 : entry + 8] = (106).to_bytes(2, "little")
    return {
        "future_zip.3dxml": (bytes(future), "not a readable zip archive (zip file version 10.6)"),
        "future_zip.zae": (bytes(future), "not a readable zip archive (zip file version 10.6)"),
        "cut.dae": (dae[: len(dae) // 2], "cannot read COLLADA file"),
        "empty.usda": (b"", "file is empty"),
        "cut.usdc": (usdc[: len(usdc) // 2], "cannot read USD file"),
        "junk.usda": (
            b'#usda 1.0\ndef Mesh "m" { point3f[] points = [(0, 0, \n',
            "cannot read USD file (line 3, column 1: syntax error at",
        ),
        "ref.usda": (f"#usda 1.0\n(\n    subLayers = [@{outside}@]\n)\n".encode(), "outside the scene's folder"),
        "url.usda": (b"#usda 1.0\n(\n    subLayers = [@http://example.com/a.usda@]\n)\n", "is a URL"),
        "latin1.usda": (b'#usda 1.0\n(\n    doc = "caf\xe9"\n)\n', "not UTF-8 text at line 3"),
        "sub_latin1.usda": (
            b"#usda 1.0\n(\n    subLayers = [@./latin1.usda@]\n)\n",
            "layer 'latin1.usda' it refers to is not UTF-8 text at line 3",
        ),
        "cut_char.usda": (b'#usda 1.0\n(\n    doc = "caf\xc3', "not UTF-8 text: it ends inside a character"),
        "text.3dxml": (b"not a zip", "not a readable zip archive"),
        "hostile.3dxml": (None, "points outside the archive"),
        "nozip.zae": (b"PK\x03\x04broken", "not a readable zip archive"),
    }


def test_bad_files_one_line_exit_2_nothing_written(tmp_path, capsys):
    for name, (content, says) in _bad_cases(tmp_path).items():
        path = tmp_path / name
        if content is not None:
            path.write_bytes(content)
        before = sorted(p.name for p in tmp_path.iterdir())
        code = main(["info", str(path)])
        lines = [x for x in capsys.readouterr().err.splitlines() if x.strip()]
        assert code == 2 and len(lines) == 1, (name, lines)
        assert lines[0].startswith(f"rtta: error: {path}: ") and says in lines[0], (name, lines[0])
        assert sorted(p.name for p in tmp_path.iterdir()) == before
        with pytest.raises(RttaError):
            load_scene(path)


def test_usd_errors_are_one_short_line():
    """usd-core's exception text: the cause, without C++ places and namespaces, the layer's
    path as line and column; an exception whose text is not UTF-8 still gives a reason."""
    from rtta.scene.readers import usd

    text = (
        "\n\tError in 'pxrInternal_v0_26_11__pxrReserved__::Sdf_TextFileFormatParser::_RaiseErrorPEGTL' "
        "at line 48 in file /opt/USD/pxr/usd/sdf/textParserHelpers.h : '/tmp/a b/c.usda:29:17: Expected } at "
        "'uniform token[]' in </p>\n'\n\tError in 'pxrInternal_v0_26_11__pxrReserved__::UsdStage::Open' at "
        "line 1287 in file /opt/USD/pxr/usd/usd/stage.cpp : 'Failed to open layer @/tmp/a b/c.usda@'"
    )
    assert usd._short(text) == "line 29, column 17: Expected } at 'uniform token[]' in </p>"
    assert usd._short("plain words\nmore") == "plain words"

    class NotUtf8(Exception):
        def __str__(self):
            raise UnicodeDecodeError("utf-8", b"\x8c", 0, 1, "invalid start byte")

    assert usd._error_text(NotUtf8()) == "a failure the library does not describe"  # no class name
