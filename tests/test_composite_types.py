"""The types of compositing's switches: SpriteDraw (what one sprite draw does, by named
constructors), and the options as StrEnums that still take the CLI's and the API's strings."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

from rtta.passes.oit import resolved_order
from rtta.passes.sprites import Depth, Kind, SpriteDraw, SpritePass
from rtta.passes.style import MODES, ORDERS, ROLES, Mode, Order, Role, Style


def test_named_constructors_give_the_combinations_compositing_uses():
    assert (SpriteDraw.opaque().kind, SpriteDraw.opaque().depth) == (Kind.OPAQUE, Depth.NEAREST)
    assert SpriteDraw.depths(farthest=True, cut=True) == SpriteDraw(Kind.OPAQUE, Depth.FARTHEST, cut=True)
    assert SpriteDraw.transparent() == SpriteDraw(Kind.BLENDED, Depth.OFF)
    context = SpriteDraw.context(desaturate=0.8, shaded=True)
    assert context == SpriteDraw(Kind.BLENDED, Depth.TESTED, shaded=True, cut=True, desaturate=0.8)
    assert (SpriteDraw.outlines().depth, SpriteDraw.halos().depth) == (Depth.OFF, Depth.TESTED)
    # collected: listed only behind a focus (no depth), or blended while listed (depth marks order errors)
    assert context.collected(clip=True, fetched=False) == dataclasses.replace(
        context, kind=Kind.COLLECTED, depth=Depth.OFF
    )
    plain = SpriteDraw.transparent().collected(clip=False, fetched=False)
    assert (plain.kind, plain.depth, plain.fetched) == (Kind.COLLECTED_BLENDED, Depth.NEAREST, False)
    fetched = SpriteDraw.transparent().collected(clip=False, fetched=True)
    assert (fetched.kind, fetched.depth, fetched.fetched) == (Kind.COLLECTED_BLENDED, Depth.OFF, True)


def test_sprite_draws_are_values_and_refuse_what_no_shader_does():
    with pytest.raises(dataclasses.FrozenInstanceError):
        SpriteDraw.opaque().cut = True  # type: ignore[misc]
    with pytest.raises(ValueError, match="outlines"):
        SpriteDraw(Kind.BLENDED, outlined=True)
    with pytest.raises(ValueError, match="first surfaces"):
        SpriteDraw(Kind.OPAQUE, fetched=True)
    assert len({SpriteDraw.opaque(), SpriteDraw.opaque(), SpriteDraw.halos()}) == 2  # hashable


def test_each_kind_picks_its_shader_variant(gl):
    """The defines (and so the `passes` names) each named draw asks for."""
    records = SimpleNamespace(border=1, scale=np.ones(4))  # what _defines reads of the records
    sprites = SpritePass(gl)
    try:
        on = lambda draw: sorted(k for k, v in sprites._defines([0, 1], draw, Style(), records).items() if v)  # noqa: E731
        assert on(SpriteDraw.opaque(shaded=True, outlined=True)) == [
            "MODE_SPRITE",
            "OUTLINE_QUAD",
            "SPRITE_OUTLINE",
            "WITH_AO",
        ]
        assert on(SpriteDraw.context(desaturate=0.8, shaded=False).collected(clip=True, fetched=True)) == [
            "FIRST_FETCHED",
            "FOCUS_CLIP",
            "MODE_COLLECT",
        ]
        assert on(SpriteDraw.transparent().collected(clip=False, fetched=False)) == ["MODE_BLEND", "MODE_COLLECT"]
        assert on(SpriteDraw.outlines()) == ["MODE_OUTLINE", "OUTLINE_QUAD"]
        assert on(SpriteDraw.halos()) == ["MODE_HALO"]
        sprites.frame(projection=object(), lens=object(), inv_view_proj=b"")
        assert "PROJECTOR" not in on(SpriteDraw.outlines()) and "LENS" not in on(SpriteDraw.opaque())
        assert {"PROJECTOR", "LENS"} <= set(on(SpriteDraw.context(desaturate=0.5, shaded=False)))
    finally:
        sprites.release()


def test_options_are_str_enums_that_take_the_old_strings():
    assert MODES == ("sprites", "transparent", "ghosted", "ghosted-ao") and Mode("ghosted-ao") is Mode.GHOSTED_AO
    assert ROLES == ("focus", "all") and ORDERS == ("auto", "object", "pixel")
    assert Mode.GHOSTED == "ghosted" and f"{Order.PIXEL}" == "pixel" and isinstance(Role.ALL, str)
    assert resolved_order("auto", "transparent") is Order.PIXEL
    assert resolved_order(Order.AUTO, Mode.GHOSTED) is Order.OBJECT and resolved_order("pixel", "ghosted") == "pixel"
    with pytest.raises(ValueError, match="order must be one of auto, object, pixel, got 'depth'"):
        resolved_order("depth", "transparent")  # type: ignore[arg-type]
    ao, edges = Style(focus={1}, ao_objects="all", edge_objects=Role.FOCUS).shaded(3)
    assert ao.tolist() == [True, True, True] and edges.tolist() == [False, True, False]
    with pytest.raises(ValueError, match="ao_objects must be one of focus, all, got 'some'"):
        Style(ao_objects="some").shaded(2)  # type: ignore[arg-type]


def test_capture_path_and_lens_shape_take_their_strings(gl):
    from rtta.errors import RttaError
    from rtta.gl.context import Capabilities, CapturePath
    from rtta.ldi.lens import Lens, LensShape

    caps = Capabilities.of(gl)
    assert caps.capture_path("gs") is CapturePath.GS and caps.capture_path(CapturePath.AUTO) in set(CapturePath)
    with pytest.raises(RttaError, match="capture path must be one of auto, vs, gs, got 'xx'"):
        caps.capture_path("xx")  # type: ignore[arg-type]
    assert Lens.shape("box", (0, 0, 0), 1.0).key == "box"
    assert Lens.shape(LensShape.SPHERE, (0, 0, 0), 1.0).key == "sphere"
    with pytest.raises(RttaError, match="unknown lens shape 'cone'"):
        Lens.shape("cone", (0, 0, 0), 1.0)  # type: ignore[arg-type]
