"""Binding points in one place (rtta.gl.bindings): every shader declares them by name, no two
bindings of one kind share a number in one program, and no Python module binds a bare number."""

import re
from pathlib import Path

import numpy as np

from rtta.gl import bindings, glsl
from rtta.gl.bindings import Image, Storage, Texture

ROOT = Path(__file__).resolve().parents[1]
STAGES = {".glsl", ".vert", ".frag", ".geom", ".comp"}
SHADERS = sorted(p.name for p in (ROOT / "shaders").iterdir() if p.suffix in STAGES)
LAYOUT = re.compile(r"layout\s*\(([^)]*)\)")
BINDING = re.compile(r"\bbinding\s*=\s*(\w+)")
# the calls that take a unit or binding number, with a digit for it
BARE = re.compile(
    r"\.use\(\s*\d|bind_to_storage_buffer\(\s*\d|bind_to_image\(\s*\d|bind_texture_array\(\s*\d"
    r"|bind_to_uniform_block\(\s*\d|_unit\s*=\s*\d|\.value\s*=\s*\d+\s*#.*\bunit\b"
)


def _bindings_of(name: str) -> list[str]:
    """The names after `binding =` in the layouts of a shader file, its includes expanded."""
    return [m.group(1) for layout in LAYOUT.finditer(glsl.read_source(name)) for m in BINDING.finditer(layout.group(1))]


def test_names_are_unique_across_kinds_and_defined_for_every_shader():
    known = bindings.names()
    assert {kind for kind, _ in known.values()} == {Texture, Image, Storage}
    assert known["ATLAS_COLOR"] == (Texture, 0) and known["LDI_LAYERS"] == (Image, 0)
    src = glsl.load("post.frag")
    for name, (_, value) in known.items():
        assert f"\n#define BINDING_{name} {value}\n" in src
    assert src.splitlines()[0] == "#version 450"


def test_every_shader_binding_uses_a_define_that_names_a_binding():
    known = bindings.names()
    seen = set()
    for name in SHADERS:
        for used in _bindings_of(name):
            assert used.startswith("BINDING_"), f"shaders/{name}: binding = {used}, not a BINDING_ define"
            assert used.removeprefix("BINDING_") in known, f"shaders/{name}: {used} is not in rtta.gl.bindings"
            seen.add(used.removeprefix("BINDING_"))
    unused = set(known) - seen
    assert not unused, f"bindings no shader declares: {sorted(unused)}"


def test_no_program_gives_one_number_to_two_bindings_of_a_kind():
    """Per shader file, and per composite program (its stages share the buffer bindings)."""
    known = bindings.names()
    programs = [[name] for name in SHADERS] + [["composite.vert", "composite.geom", "composite.frag"]]
    for files in programs:
        taken: dict[tuple[type, int], str] = {}
        for name in files:
            for used in _bindings_of(name):
                key = known[used.removeprefix("BINDING_")]
                other = taken.setdefault(key, used)
                assert other == used, f"{files}: {other} and {used} are both {key[0].__name__} {key[1]}"


def test_the_python_side_binds_by_name():
    bare = []
    for folder in ("rtta", "viewer"):
        for path in (ROOT / folder).rglob("*.py"):
            for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
                if BARE.search(line):
                    bare.append(f"{path.relative_to(ROOT)}:{i}: {line.strip()}")
    assert not bare, bare
    assert BARE.search("tex.use(3)") and BARE.search("b.bind_to_storage_buffer( 2)")
    assert not BARE.search("tex.use(Texture.ATLAS_COLOR)") and not BARE.search("fbo.use()")


def test_programs_see_the_units_python_binds(gl):
    """The sampler uniforms of compiled composite variants hold the units from the module."""
    stages = {
        "vertex_shader": "composite.vert",
        "geometry_shader": "composite.geom",
        "fragment_shader": "composite.frag",
    }
    expected = {
        "u_color": Texture.ATLAS_COLOR,
        "u_depth": Texture.ATLAS_DEPTH,
        "u_post": Texture.ATLAS_POST,
        "u_normal": Texture.ATLAS_NORMAL,
        "u_projector_image": Texture.PROJECTOR_IMAGE,
        "u_projector_depth": Texture.PROJECTOR_DEPTH,
        "u_context_depth": Texture.CONTEXT_DEPTH,
        "u_focus_depth": Texture.FOCUS_DEPTH,
    }
    seen = set()
    for defines in (
        {"MODE_HALO": True},
        {"MODE_SPRITE": True, "WITH_AO": True, "PROJECTOR": True},
        {"MODE_COLLECT": True, "FOCUS_CLIP": True},
    ):
        prog = glsl.program(gl, **glsl.stage_sources(stages, **defines))
        try:
            for name, unit in expected.items():
                if name in prog:
                    assert prog[name].value == unit, (defines, name)
                    seen.add(name)
        finally:
            prog.release()
    assert seen == set(expected)


def test_a_lens_and_a_projector_in_one_draw_keep_their_own_units(make_renderer, demo_scene):
    """The lens's LDI ranges were bound on the projector's shadow-map unit: with both, the
    context's projection read the ranges as its depth. A lens that cuts nothing changes nothing."""
    from rtta.ldi.lens import Lens
    from rtta.passes.composite import Style
    from rtta.passes.projector import Projector
    from rtta.scene.camera import Camera

    r = make_renderer(demo_scene)
    cam = Camera.orbit(demo_scene.center, demo_scene.radius, 35, 25, 2.2)
    r.projector = Projector.orbit(demo_scene.center, demo_scene.radius, 60, 35, 2.5, fov_y=35.0)
    r.capture(cam, (160, 120))
    style = Style(focus={0})
    plain = r.composite("ghosted", style).read()[0]
    far = demo_scene.center + 50 * demo_scene.radius
    r.lens = Lens.shape("sphere", far, 0.01 * demo_scene.radius)
    assert np.array_equal(r.composite("ghosted", style).read()[0], plain)
    r.projector = None
    assert not np.array_equal(r.composite("ghosted", style).read()[0], plain)  # the projection shows
