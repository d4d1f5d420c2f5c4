"""Binding points, in one place: the texture units, image units and shader storage buffer
bindings the Python side binds to and the shaders declare.

The shader loader (`glsl.load`) gives every shader each of them as `#define BINDING_<NAME> <n>`
(`defines()`), and the shaders declare `layout(binding = BINDING_<NAME>)`; the Python side binds
with the same names (`texture.use(Texture.ATLAS_COLOR)`, `buf.bind_to_storage_buffer(Storage.RECORDS)`).
tests/test_bindings.py checks that no shader and no Python module uses a bare number.

Each namespace is per program: two bindings may share a number where no program declares both
(the test checks each shader's own). To add one: a name here, `layout(binding = BINDING_<NAME>)`
in the shader, the same name where Python binds it. Names are unique across the three classes.
"""

from __future__ import annotations

from typing import Final


class Texture:
    """Texture units of samplers (`texture.use(unit)`, `glraw.bind_texture_array(unit, glo)`)."""

    ATLAS_COLOR: Final = 0  # composite.frag: the atlas colour images
    ATLAS_DEPTH: Final = 1  # composite.frag, post.frag, view.frag: the depth-keyed atlas depth
    LDI_RANGES: Final = 2  # ldi_classify.comp: a compressed LDI's depth ranges (also the lens's, ldi/lens.py)
    ATLAS_POST: Final = 3  # composite.frag: (ao, edge) per atlas texel (post.frag's output, ghosted-ao)
    ATLAS_NORMAL: Final = 4  # composite.frag (projector), post.frag: the atlas view-space normals
    PROJECTOR_IMAGE: Final = 5  # projector.glsl: the projected image
    PROJECTOR_DEPTH: Final = 6  # projector.glsl: the projector's shadow map
    FOCUS_DEPTH: Final = 7  # composite.frag: nearest focus sprite depth per pixel (MODE_COLLECT)
    CONTEXT_DEPTH: Final = 8  # composite.frag: farthest context sprite depth per pixel (MODE_HALO)
    TARGET_DEPTH: Final = 9  # blend_tiles.comp: the composite's depth (the focus sprites'), tested against
    MATERIAL_ATLAS: Final = 15  # material.glsl: the scene's material atlas (textured scenes)
    SCENE_TEXTURE: Final = 0  # scene.frag (SEPARATE): the one object's own texture
    VIEW_TEXTURE: Final = 0  # view.frag: the texture shown (a composite, or an atlas colour layer)
    PEEL_PREVIOUS: Final = 0  # ldi_peel.frag: layer k-1 of depth peeling
    LDI_POINTS: Final = 0  # ldi_classify.comp: the points tested (a buffer texture)
    OIT_FIRST: Final = 0  # oit_resolve.frag (FIRST_FETCHED): each pixel's first two surfaces
    OIT_MORE: Final = 1  # oit_resolve.frag (FIRST_FETCHED): its third and the list of the later ones


class Image:
    """Image units (`texture.bind_to_image(unit, ...)`)."""

    LDI_LAYERS: Final = 0  # ldi.glsl: an LDI's layers (r32f)
    LDI_INSIDE: Final = 1  # ldi_classify.comp: the result per point (r8ui)
    TARGET_COLOR: Final = 2  # blend_tiles.comp: the composite's colour, blended into (rgba8)


class Storage:
    """Shader storage buffer bindings (`buffer.bind_to_storage_buffer(binding)`)."""

    RECORDS: Final = 0  # records.glsl: R, one record per object id
    OBJECTS: Final = 1  # records.glsl: object colours
    MATERIALS: Final = 2  # material.glsl: per object, its place in the material atlas
    STYLES: Final = 2  # composite.glsl: per object (opacity, focus, ao, edges)
    DRAW_LIST: Final = 3  # composite.glsl, post.vert: the object ids a draw covers, in order
    BOUNDS: Final = 4  # composite.geom: B_world per object
    OIT_HEADS: Final = 5  # oit.glsl: per pixel, its list's first node
    OIT_NODES: Final = 6  # oit.glsl: the lists' nodes
    OIT_BASES: Final = 7  # composite.geom: per object, its first node (one per pixel of its sprite)
    PLACEMENT: Final = 8  # section.glsl: per object, its explode offset and cut flags (cutaways)
    PARAM_CORNERS: Final = 9  # parameterize.comp: B_world's corners per object (doubles)
    PARAM_SCALES: Final = 10  # parameterize.comp: the region scale wanted per object (0: hidden)
    PARAM_ITEMS: Final = 11  # parameterize.comp: per object, its rectangle, size and place
    PARAM_CLASSES: Final = 12  # parameterize.comp: per height class, its shelves and layers
    PARAM_STATE: Final = 13  # parameterize.comp: layers, used size, the scale-down factor
    PARAM_SHELVES: Final = 14  # parameterize.comp: per shelf, its layer and height
    PARAM_OFFSETS: Final = 15  # parameterize.comp: per object, its explode offset (doubles)
    PARAM_DISPATCH: Final = 22  # parameterize.comp: the next round's indirect dispatch sizes (0 once done)
    PARAM_THIN: Final = 23  # parameterize.comp: fast navigation's area classes, their counts and the cut
    PARAM_WEIGHTS: Final = 24  # parameterize.comp: per object, its triangles and whether it is protected
    SORT_KEYS: Final = 16  # depth_order.comp: the sort's keys (ids sorted with them in DRAW_LIST)
    COMPOSITE_COMMAND: Final = 17  # depth_order.comp: compositing's indirect DrawArrays command (the count drawn)
    SORT_OFFSETS: Final = 18  # depth_order.comp: per object, an offset of its bounds centre (floats)
    SORT_KEYS_OUT: Final = 19  # depth_order.comp: a radix pass's keys out (SORT_KEYS: in)
    SORT_IDS_OUT: Final = 20  # depth_order.comp: a radix pass's ids out (DRAW_LIST: in)
    SORT_COUNTS: Final = 21  # depth_order.comp: a radix pass's digit counts per tile, then their offsets
    DRAW_FLAGS: Final = 2  # capture_lists.comp: per object, closed and cut away whole
    DRAW_RANGES: Final = 3  # capture_lists.comp: per object, its (first, count) in the index buffer
    DRAW_COMMANDS: Final = 5  # capture_lists.comp: the capture's indirect draw commands, a list per kind
    DRAW_COUNTS: Final = 6  # capture_lists.comp: the commands in each kind's list


KINDS: Final = (Texture, Image, Storage)


def names() -> dict[str, tuple[type, int]]:
    """Every binding point.

    Returns
    -------
    dict of str to (type, int)
        Name -> (its class: Texture, Image or Storage; its number).

    Raises
    ------
    ValueError
        A name is given in two classes (the shader defines would clash).
    """
    out: dict[str, tuple[type, int]] = {}
    for kind in KINDS:
        for name, value in vars(kind).items():
            if name.isupper():
                if name in out:
                    raise ValueError(f"binding {name} is named in both {out[name][0].__name__} and {kind.__name__}")
                out[name] = (kind, int(value))
    return out


def defines() -> dict[str, int]:
    """What the shader loader defines in every shader.

    Returns
    -------
    dict of str to int
        `BINDING_<NAME>` -> number, for every binding of `names()`.
    """
    return {f"BINDING_{name}": value for name, (_, value) in names().items()}
