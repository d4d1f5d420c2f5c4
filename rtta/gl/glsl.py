"""The one GLSL loader: files shipped in the package `rtta.shaders`, cached,
`#include "file"` resolved, defines injected after `#version`; unknown defines rejected.
Every shader also gets the binding points of `bindings` as `#define BINDING_<NAME> <n>`.

Each shader file declares the defines it understands on a line `// defines: A B C`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from functools import cache
from importlib import resources
from typing import TYPE_CHECKING

import numpy as np

from ..outputs import signals_held
from . import bindings

if TYPE_CHECKING:
    import moderngl

_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$', re.MULTILINE)
_DECLARED = re.compile(r"^//\s*defines:(.*)$", re.MULTILINE)
_BINDINGS = tuple(bindings.defines().items())  # after the pass's own defines


@cache
def read_source(name: str) -> str:
    """Raw text of a shader file, with includes expanded (one level deep is enough here)."""
    text = resources.files("rtta.shaders").joinpath(name).read_text(encoding="utf-8")
    return _INCLUDE.sub(lambda m: read_source(m.group(1)), text)


def declared_defines(name: str) -> set[str]:
    out: set[str] = set()
    for m in _DECLARED.finditer(read_source(name)):
        out.update(m.group(1).split())
    return out


@cache
def _load(name: str, defines: tuple[tuple[str, str], ...]) -> str:
    known = declared_defines(name)
    unknown = sorted(k for k, _ in defines if k not in known)
    if unknown:
        raise ValueError(f"shader {name}: unknown define(s) {', '.join(unknown)}; known: {sorted(known)}")
    text = read_source(name)
    first, _, rest = text.partition("\n")
    if not first.startswith("#version"):
        raise ValueError(f"shader {name}: first line must be #version")
    extra = "".join(f"#define {k} {v}\n" for k, v in (*defines, *_BINDINGS))
    return f"{first}\n{extra}#line 2\n{rest}"


def load(name: str, **defines: object) -> str:
    """Shader source with `defines` (name=value; True means 1) injected after #version."""
    items = tuple(sorted((k, "1" if v is True else str(v)) for k, v in defines.items() if v is not False))
    return _load(name, items)


def stage_sources(stages: Mapping[str, str | None], **defines: object) -> dict[str, str | None]:
    """Sources for `ctx.program(**...)`: each stage (keyword -> file, or None) gets the defines
    its own file declares; a define that no stage declares is rejected."""
    known = set().union(*(declared_defines(name) for name in stages.values() if name))
    unknown = sorted(set(defines) - known)
    if unknown:
        raise ValueError(f"no shader of this pass declares {', '.join(unknown)}")
    return {
        stage: load(name, **{k: v for k, v in defines.items() if k in declared_defines(name)}) if name else None
        for stage, name in stages.items()
    }


def program(
    ctx: moderngl.Context,
    vertex_shader: str | None = None,
    fragment_shader: str | None = None,
    geometry_shader: str | None = None,
) -> moderngl.Program:
    """`ctx.program(...)` with signals held (rtta.outputs.signals_held), raised once the
    program is made: moderngl builds a program's members through Python calls, and an
    interrupt raised among them crashed the process (SIGSEGV inside Context.program; 3 of 3
    runs of 200 interrupted frames on llvmpipe, none in 800 with the hold)."""
    with signals_held():
        return ctx.program(
            vertex_shader=vertex_shader, fragment_shader=fragment_shader, geometry_shader=geometry_shader
        )


def uniform(prog: moderngl.Program | moderngl.ComputeShader, name: str) -> moderngl.Uniform:
    """`prog[name]` as the uniform it is, for `.value` and `.write`.

    moderngl types a program's members as any kind (uniform, uniform block, attribute,
    varying), and only a uniform has both; this says which one the caller means.

    Parameters
    ----------
    prog : moderngl.Program or moderngl.ComputeShader
        The program holding the uniform.
    name : str
        The uniform's name in the shader (a KeyError where the compiler dropped it).

    Returns
    -------
    moderngl.Uniform
        ``prog[name]``, unchanged.
    """
    return prog[name]  # type: ignore[return-value]  # (no typing.cast: a call, ~90 a frame)


def set_uniform(prog: moderngl.Program | moderngl.ComputeShader, name: str, value) -> None:
    """`prog[name]` set to `value` (bytes written as they are), skipped where the program holds
    it already: the values set through here are kept in `prog.extra`, so a program's uniforms
    must be set through here alone. For the calls made every frame (a few dozen of them).

    Parameters
    ----------
    prog : moderngl.Program or moderngl.ComputeShader
        The program holding the uniform.
    name : str
        The uniform's name in the shader.
    value : bytes, bool, int, float or tuple
        What to set (not an array: values are compared with ==).
    """
    held = prog.extra
    if held is None:
        held = prog.extra = {}
    if name in held and held[name] == value:
        return
    held[name] = value
    if isinstance(value, bytes):
        prog[name].write(value)  # type: ignore[union-attr]
    else:
        prog[name].value = value  # type: ignore[union-attr]


def set_uniforms(prog: moderngl.Program | moderngl.ComputeShader, values: dict) -> None:
    """`set_uniform` for each of `values` that `prog` holds (`has`: the compiler drops what a
    variant does not use), in one call: a draw's dozen uniforms cost one Python call, not two
    dozen (issue 43: a frame's CPU cost is counted in calls).

    Parameters
    ----------
    prog : moderngl.Program or moderngl.ComputeShader
        The program holding the uniforms.
    values : dict
        Uniform name -> value, as `set_uniform` takes it; names the program lacks are skipped.
    """
    held = prog.extra  # _held(prog), without its call
    if held is None:
        held = prog.extra = {}
    names = held.get("__members__")
    if names is None:
        names = held["__members__"] = frozenset(prog)
    for name, value in values.items():
        if name in names and (name not in held or held[name] != value):
            held[name] = value
            if value.__class__ is bytes:
                prog[name].write(value)  # type: ignore[union-attr]
            else:
                prog[name].value = value  # type: ignore[union-attr]


def has(prog: moderngl.Program | moderngl.ComputeShader, name: str) -> bool:
    """Whether `prog` holds a member `name` (the compiler drops what a variant does not use).
    `name in prog` walks every member; the names are kept in `prog.extra` (as set_uniform's
    values are: "__members__" is no GLSL name) after the first question."""
    return name in _held(prog)[1]


def members(prog: moderngl.Program | moderngl.ComputeShader) -> frozenset[str]:
    """The names of `prog`'s members (uniforms, blocks, attributes), kept as `has` keeps them."""
    return _held(prog)[1]


def _held(prog: moderngl.Program | moderngl.ComputeShader) -> tuple[dict, frozenset]:
    """`prog.extra` (made on first use) and the program's member names, kept there."""
    held = prog.extra
    if held is None:
        held = prog.extra = {}
    names = held.get("__members__")
    if names is None:
        names = held["__members__"] = frozenset(prog)
    return held, names


F32_MAX = float(np.finfo(np.float32).max)


def mat_bytes(m: np.ndarray) -> bytes:
    """Row-major float64 4x4 -> column-major float32 bytes for a GLSL mat4 (entries past
    float32's range saturate: an inf would be NaN in a shader)."""
    m = np.minimum(np.maximum(np.asarray(m, np.float64), -F32_MAX), F32_MAX)  # np.clip: 5 Python calls more
    return m.T.astype(np.float32, order="C").tobytes()
