"""What compositing is asked for besides the atlas: the mode, and the Style (opacities, the
focus set, colours, widths, which objects get AO and edges, the blending order, halos).

Options are `StrEnum`s where the code compares them (`Mode`, `Role`, `Order`) and `Literal`
aliases in the type hints of the public API (`ModeName`, `RoleName`, `OrderName`): the CLI's
and the API's strings stay what they were, and a str equal to a value works as the member.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import Literal, TypeVar

import numpy as np

from ..errors import member


class Mode(StrEnum):
    """Compositing modes (RTTA paper, section 3.2; docs/modes.md)."""

    SPRITES = "sprites"  # depth sprites: STD reconstructed
    TRANSPARENT = "transparent"  # every object blended with its opacity, back to front
    GHOSTED = "ghosted"  # focus opaque, visible through the faded, desaturated context
    GHOSTED_AO = "ghosted-ao"  # ghosted, shaded with AO and edges from each object's own atlas images


class Role(StrEnum):
    """Which objects get AO / edges in ghosted-ao (Style.ao_objects, Style.edge_objects)."""

    FOCUS = "focus"  # the focus objects only (the paper's AO)
    ALL = "all"


class Order(StrEnum):
    """The blending order of `transparent` and the ghosted context (oit.resolved_order)."""

    AUTO = "auto"  # pixel in `transparent`, object for the ghosted context
    OBJECT = "object"  # back to front by bounds centre
    PIXEL = "pixel"  # per pixel, by surface depth (oit.PixelOrderPass)


ModeName = Literal["sprites", "transparent", "ghosted", "ghosted-ao"]
RoleName = Literal["focus", "all"]
OrderName = Literal["auto", "object", "pixel"]
MODES: tuple[str, ...] = tuple(m.value for m in Mode)
ROLES: tuple[str, ...] = tuple(r.value for r in Role)
ORDERS: tuple[str, ...] = tuple(o.value for o in Order)
LENS_MODES: tuple[str, ...] = (Mode.GHOSTED.value, Mode.GHOSTED_AO.value)  # where a lens cuts the context away
BACKGROUND = (0.93, 0.93, 0.95, 1.0)


E = TypeVar("E", bound=StrEnum)


def choice(kind: type[E], value: str, what: str) -> E:
    """`value` as a member of `kind`.

    Parameters
    ----------
    kind : type of StrEnum
        The option's enum (Mode, Role, Order).
    value : str
        A member or its string.
    what : str
        The option's name, for the message.

    Returns
    -------
    StrEnum
        The member of `kind` equal to `value`.

    Raises
    ------
    ValueError
        `value` is none of them: "<what> must be one of <choices>, got <value>".
    """
    found = member(kind, value)
    if found is None:
        raise ValueError(f"{what} must be one of {', '.join(kind)}, got {value!r}")
    return found


@dataclass
class Style:
    """How a capture is composited: focus, opacities, colours, widths, AO, order, halos.

    Changing it never re-runs the capture, and only the objects whose role changed are shaded
    again. `rtta.snapshot` takes these fields as keywords; the CLI as options of the same names
    (`--context-opacity`, `--ao-objects` ...). The defaults come from `rtta bench composite` on
    the demo at 1024² (docs: Performance, Compositing modes).

    Parameters
    ----------
    opacity : dict of int to float
        Opacity per object id, in `transparent`.
    default_opacity : float, default 0.5
        Opacity of the objects not in `opacity`, in `transparent`.
    focus : set of int
        The focus set: highlighted objects, opaque in the ghosted modes, outlined in all.
    context_opacity : float, default 0.3
        Opacity of everything else in the ghosted modes.
    desaturate : float, default 0.8
        How far the context's colours are desaturated (0: not at all, 1: grey).
    edge_color, outline_color : tuple of float
        RGBA of the `ghosted-ao` edges and of the focus objects' silhouettes.
    outline_width, edge_width : int, default 1
        Widths in pixels.
    ao_radius : float, default 6
        Ambient occlusion radius in pixels (`ghosted-ao`).
    ao_strength : float, default 1
        Ambient occlusion strength.
    ao_objects : {"focus", "all"}, default "focus"
        Which objects get AO in `ghosted-ao` (the paper's: the focus).
    edge_objects : {"focus", "all"}, default "all"
        Which objects get edges in `ghosted-ao`.
    order : {"auto", "object", "pixel"}, default "auto"
        Blending order of `transparent` and of the ghosted context: by bounds centre, per pixel
        by surface depth, or auto (per pixel in `transparent`, by object in the context).
    halo : int, default 0
        Width in pixels of a halo around the focus objects where context lies behind (0: none).
    halo_color : tuple of float
        The halo's RGB and strength.

    Examples
    --------
    >>> import rtta
    >>> style = rtta.Style(focus={17, 18}, context_opacity=0.2, ao_objects="all", halo=4)
    """

    opacity: dict[int, float] = field(default_factory=dict)  # per object id
    default_opacity: float = 0.5  # `transparent`: objects not in `opacity`
    focus: set[int] = field(default_factory=set)
    context_opacity: float = 0.3
    desaturate: float = 0.8
    edge_color: tuple[float, float, float, float] = (0.05, 0.05, 0.08, 1.0)
    outline_color: tuple[float, float, float, float] = (1.0, 0.75, 0.1, 1.0)
    outline_width: int = 1
    edge_width: int = 1
    ao_radius: float = 6.0
    ao_strength: float = 1.0
    # defaults from `rtta bench composite` on the demo at 1024² (docs/performance/modes.md)
    ao_objects: RoleName | Role = "focus"  # ghosted-ao: AO on 'focus' objects only (the paper) or on 'all'
    edge_objects: RoleName | Role = "all"  # ghosted-ao: edges on 'focus' objects only or on 'all'
    order: OrderName | Order = "auto"  # transparent and ghosted context: 'object' (bounds centres), 'pixel'
    # (surface depths), or 'auto' (oit.resolved_order: pixel in transparent)
    halo: int = 0  # ghosted modes: halo width (pixels) around focus objects, 0: none
    halo_color: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.6)  # (rgb, strength)

    def shaded(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(uses AO, uses edges) per object [n] bool, in ghosted-ao."""
        focus = np.zeros(n, bool)
        focus[[o for o in self.focus if 0 <= o < n]] = True
        every = np.ones(n, bool)
        ao, edges = (choice(Role, getattr(self, name), name) for name in ("ao_objects", "edge_objects"))
        return (every if ao is Role.ALL else focus), (every if edges is Role.ALL else focus)


def style_params(style: Style, mode: Mode, n: int, *, faded: bool = False) -> np.ndarray:
    """Compositing's style parameters per object (composite.glsl's Style): [max(n, 1), 4]
    float32 of (opacity, focus, uses AO, uses edges).

    Parameters
    ----------
    style : Style
        Opacities, focus, and the roles of AO and edges (ghosted-ao).
    mode : Mode
        `transparent` takes `style.default_opacity` where `style.opacity` names none, the
        other modes 1; `ghosted-ao` gives the AO and edge roles.
    n : int
        Objects.
    faded : bool, default False
        The context's opacities times `style.context_opacity` (the ghosted context's blend).

    Returns
    -------
    numpy.ndarray
        The parameters, row `i` object `i`'s.
    """
    params = np.zeros((max(n, 1), 4), np.float32)
    params[:n, 0] = style.default_opacity if mode is Mode.TRANSPARENT else 1.0
    for oid, a in style.opacity.items():
        params[oid, 0] = float(np.clip(a, 0.0, 1.0))
    focus = focus_ids(style, n)
    params[focus, 1] = 1.0
    if mode is Mode.GHOSTED_AO:
        ao, edges = style.shaded(n)
        params[:n, 2], params[:n, 3] = ao, edges
    if faded:
        context = np.ones(n, bool)
        context[focus] = False
        params[:n][context, 0] = style.context_opacity * params[:n][context, 0]
    return params


def focus_ids(style: Style, n: int) -> np.ndarray:
    """The focus objects among `n`, ascending (int64)."""
    ids = np.array(sorted(style.focus), np.int64)
    return ids[(ids >= 0) & (ids < n)]


def style_key(style: Style, mode: Mode, n: int) -> tuple:
    """What `style_params` depends on, to build and upload them only when it changes
    (the work of it grows with the opacities and focus named, not with `n`)."""
    return (
        mode,
        n,
        style.default_opacity,
        tuple(sorted(style.opacity.items())),
        tuple(sorted(style.focus)),
        style.context_opacity,
        str(style.ao_objects),
        str(style.edge_objects),
    )
