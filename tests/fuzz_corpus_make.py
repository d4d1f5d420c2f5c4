"""The seed corpora of the fuzz targets (tests/fuzz_targets.py), built from the tests' own
files: `python scripts/fuzz.py --corpus` writes tests/fuzz_corpus/<target>/ (small files only:
at most MAX_SEED bytes each)."""

from __future__ import annotations

import base64
import json
import struct
import tempfile
from pathlib import Path

from bad_files import OBJ_TRI
from bad_gltf import box_doc, glb, gltf_error_files, gltf_loading_files

MAX_SEED = 16 * 1024


def _as_gltf(data: bytes) -> bytes:
    """A GLB as a .gltf: its JSON with the binary chunk as a base64 data: URI."""
    n = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + n])
    binary = data[28 + n :]
    for buf in doc.get("buffers", [])[:1]:
        buf["uri"] = "data:application/octet-stream;base64," + base64.b64encode(binary).decode()
    return json.dumps(doc, indent=1).encode()


def gltf_seeds() -> dict[str, bytes]:
    out = {name: data for name, (data, _) in gltf_loading_files().items()}
    out.update({name: data for name, (data, _) in gltf_error_files().items()})
    hidden = [
        {"name": "root", "children": [1, 2]},
        {"name": "shown", "mesh": 0},
        {"name": "gone", "mesh": 0, "scale": [1, 0, 1]},
    ]
    out["hidden_node.glb"] = glb(*box_doc(hidden))
    for name in ("names_two_primitives.glb", "pictures_fan_beside_triangles.glb", "hidden_node.glb"):
        out[name.replace(".glb", ".gltf")] = _as_gltf(out[name])
    doc, binary = box_doc()
    doc["accessors"][0]["sparse"] = {
        "count": 1,
        "indices": {"bufferView": 2, "componentType": 5123},
        "values": {"bufferView": 0},
    }
    out["sparse.glb"] = glb(doc, binary)
    return out


def obj_seeds() -> dict[str, bytes]:
    box = "".join(f"v {x} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 2))
    quads = "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"
    texts = {
        "triangle.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "with_uv.obj": OBJ_TRI + "vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n",
        "two_objects.obj": f"o a\n{box}{quads}o b\n{box.replace('v 1', 'v 3')}"
        + quads.replace(" ", " -").replace("f -", "f "),
        "groups.obj": f"g left\n{box}{quads}g right\n{box}{quads}",
        "negative.obj": f"o n\n{box}f -8 -7 -5 -6\nf -4 -3 -1\n",
        "crlf.obj": f"o a\r\n{box}{quads}".replace("\n", "\r\n"),
        "materials.obj": f"mtllib parts.mtl\no a\nusemtl red\n{box}{quads}o b\nusemtl blue\n{box}{quads}",
        "slashes.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1//1 2//1 3//1\nf 1/1 2/1 3/1\n",
        "polygon.obj": "o p\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 1.5 0\nv 0 1 0\nf 1 2 3 4 5\n",
        "latin1_names.obj": "o caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nv 0 0 1\nf 1 2 4\n",
        "continuation.obj": "o a\nv 0 0 \\\n0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    }
    return {name: text.encode("latin-1") for name, text in texts.items()}


STEP_HEAD = "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('seed'),'2;1');\nENDSEC;\nDATA;\n"
STEP_TAIL = "ENDSEC;\nEND-ISO-10303-21;\n"


def step_seeds() -> dict[str, bytes]:
    units = (
        "#1=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));\n"
        "#2=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));\n"
        "#3=(CONVERSION_BASED_UNIT('INCH',#4)LENGTH_UNIT()NAMED_UNIT(#5));\n"
        "#6=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2))REPRESENTATION_CONTEXT('',''));\n"
        "#7=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNIT_ASSIGNED_CONTEXT((#3,#2))REPRESENTATION_CONTEXT('',''));\n"
    )
    products = (
        "#10=PRODUCT('engine','engine','',(#9));\n#11=PRODUCT('block','block','',(#9));\n"
        "#12=PRODUCT('it''s','x','',(#9));\n"
        "#20=PRODUCT_DEFINITION_FORMATION('','',#10);\n#21=PRODUCT_DEFINITION_FORMATION('','',#11);\n"
        "#22=PRODUCT_DEFINITION_FORMATION_WITH_SPECIFIED_SOURCE('','',#12,.NOT_KNOWN.);\n"
        "#30=PRODUCT_DEFINITION('design','',#20,#8);\n#31=PRODUCT_DEFINITION('design','',#21,#8);\n"
        "#32=PRODUCT_DEFINITION('design','',#22,#8);\n"
        "#40=NEXT_ASSEMBLY_USAGE_OCCURRENCE('1','','',#30,#31,$);\n"
        "#41=NEXT_ASSEMBLY_USAGE_OCCURRENCE('2','','',#30,#32,$);\n"
        "#42=NEXT_ASSEMBLY_USAGE_OCCURRENCE('3','','',#32,#31,$);\n"
    )
    out = {
        "units_and_products.step": STEP_HEAD + units + products + STEP_TAIL,
        "external.step": STEP_HEAD + "#1=DOCUMENT_FILE('../other.stp','',$,#2,'',$);\n" + STEP_TAIL,
        "no_trailer.step": STEP_HEAD + units,
        "bom.step": "\ufeff" + STEP_HEAD + STEP_TAIL,
    }
    seeds = {name: text.encode("latin-1", "replace") for name, text in out.items()}
    try:
        from assemblies import write_step
    except ImportError:
        return seeds
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "engine.step"
        write_step(path)
        data = path.read_bytes()
        if len(data) <= 4 * MAX_SEED:  # the tests' assembly: the real thing's entities
            seeds["engine.step"] = data
    return seeds


def ifc_seeds() -> dict[str, bytes]:
    """Element graphs as fuzz_ifc reads them: count, types and names, then (op, a, b) triples."""
    chains = {
        "tree.bin": bytes([6, 0, 0, 1, 2, 2, 3, 3, 4, 4, 1, 5, 5, 0, 0, 1, 0, 1, 2, 0, 2, 3, 1, 3, 4, 1, 3, 5]),
        "cycle.bin": bytes([4, 3, 1, 3, 2, 3, 3, 3, 4, 0, 0, 1, 0, 1, 2, 0, 2, 3, 0, 3, 0]),
        "opening.bin": bytes([5, 3, 2, 4, 3, 6, 1, 5, 4, 0, 0, 1, 1, 0, 2, 2, 2, 3, 2, 3, 4, 3, 1, 4]),
        "shared.bin": bytes([5, 0, 0, 3, 1, 3, 2, 7, 3, 4, 4, 0, 0, 1, 0, 0, 2, 0, 1, 3, 0, 2, 3, 1, 3, 4]),
    }
    return chains


def specs_seeds() -> dict[str, bytes]:
    texts = {
        "orbit.txt": "30,20,3\x001024x768",
        "orbit_fit.txt": "-45,35.26\x00bolt=0.5",
        "size.txt": "1920X1080\x00frame=1",
        "opacity.txt": "bolt=0.25\x00cover plate*=1",
        "group.txt": "frame/*\x00frame=0",
        "lens.txt": "sphere,2\x001,2,3",
        "lens_object.txt": "bolt\x00",
        "color.txt": "0.1,0.2,0.3,1\x000,0,0,1",
        "exotic.txt": "1e308,-0,nan\x00inf=0.5",
        "glob.txt": "[a-\x00**",
        "section.txt": "-x=0.5",
        "section_plane.txt": "0.6,0,0.8,-1e3",
    }
    return {name: text.encode() for name, text in texts.items()}


def views_seeds() -> dict[str, bytes]:
    """Saved view files (rtta.renderer.view_file, version 1) and dataset --cameras files."""
    full = {
        "rtta_view": 1,
        "camera": {"az": 35.0, "el": 25.0, "distance": 4.1, "target": [0.0, 0.1, 0.0], "fov": 45.0},
        "projection": "ortho",
        "mode": "ghosted-ao",
        "focus": ["bolt"],
        "hidden": ["frame/*"],
        "opacity": {"cover plate*": 0.3},
        "style": {"edge_width": 1, "ao_radius": 6.0},
        "sections": {"planes": ["x=0.5", "0,1,0,0"], "caps": "hatch", "scope": "context"},
        "explode": {"factor": 0.5, "scope": "context"},
    }
    docs = {
        "view_full.json": full,
        "view_minimal.json": {"rtta_view": 1},
        "view_newer.json": {"rtta_view": 2},
        "view_camera_only.json": {"rtta_view": 1, "camera": full["camera"]},
        "cameras_orbit.json": [{"orbit": [30, 20, 3], "fov": 40}, {"orbit": [-90, 80, 1.5]}],
        "cameras_eye.json": [{"eye": [3, 2, 1], "target": [0, 0, 0], "up": [0, 0, 1], "fov": 60}],
    }
    return {name: json.dumps(doc, indent=1).encode() for name, doc in docs.items()}


def cache_sources() -> dict[str, bytes]:
    """The small files whose cache entries the cache target mutates (tests/fuzz_cache.py): a
    triangle, OBJ parts with their materials file, a glTF tree of groups, a textured GLB and a
    .gltf whose buffer is a file of its own."""
    from bad_gltf import _textured, png

    quad = "v 0 0 {z}\nv 1 0 {z}\nv 1 1 {z}\nv 0 1 {z}\n"
    parts = "mtllib parts.mtl\no first\n" + quad.format(z=0) + "usemtl red\nf 1 2 3\nf 1 3 4\n"
    parts += "o second\n" + quad.format(z=1) + "usemtl blue\nf 5 6 7\nf 5 7 8\n"
    nodes = [
        {"name": "frame", "children": [1, 2, 3]},
        {"name": "bolt", "mesh": 0},
        {"name": "bolt", "mesh": 0, "translation": [2, 0, 0]},
        {"name": "cover plate", "mesh": 0, "translation": [0, 2, 0]},
    ]
    doc, binary = box_doc([{"mesh": 0, "name": "box"}])
    doc["buffers"] = [{"byteLength": len(binary), "uri": "box.bin"}]
    return {
        "triangle.obj": b"o tri\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "parts.obj": parts.encode(),
        "parts.mtl": b"newmtl red\nKd 0.8 0.1 0.1\nnewmtl blue\nKd 0.1 0.2 0.9\n",
        "tree.glb": glb(*box_doc(nodes)),
        "textured.glb": _textured(png((4, 4))),
        "box.gltf": json.dumps(doc).encode(),
        "box.bin": binary,
    }


def cache_seeds(where: Path) -> dict[str, bytes]:
    """The cache target's sources into where/sources/, and the entries the cache writes for them."""
    from fuzz_cache import seeds

    (where / "sources").mkdir(parents=True, exist_ok=True)
    for name, data in cache_sources().items():
        (where / "sources" / name).write_bytes(data)
    return seeds(where)


def write_corpus(folder: Path, targets: list[str] | None = None) -> dict[str, int]:
    """The seeds of `targets` (default: all) into folder/<target>/, replacing what was there
    but the inputs fuzzing found (found_*); {target: count written}."""
    makers = {
        "gltf": gltf_seeds,
        "obj": obj_seeds,
        "step": step_seeds,
        "ifc": ifc_seeds,
        "specs": specs_seeds,
        "views": views_seeds,
        "cache": lambda: cache_seeds(folder / "cache"),
    }
    counts = {}
    for target in targets or list(makers):
        seeds = makers[target]()
        where = folder / target
        where.mkdir(parents=True, exist_ok=True)
        for old in where.iterdir():  # the inputs fuzzing found (found_*) stay: regression seeds
            if old.is_file() and not old.name.startswith("found_"):
                old.unlink()
        kept = {name: data for name, data in seeds.items() if len(data) <= (4 if target == "step" else 1) * MAX_SEED}
        for name, data in kept.items():
            (where / name).write_bytes(data)
        counts[target] = len(kept)
    return counts
