"""Why a library failed, said in the user's terms (issue 42): rtta.errors.reason never gives
an exception's class or Python's own wording, and the messages built on it (unreadable
archives, textures, files) name none either."""

from __future__ import annotations

import numpy as np
import pytest
from bad_files import threemf_bad_deflate
from bad_gltf import _textured, png
from PIL import UnidentifiedImageError

from rtta.errors import RttaError, reason
from rtta.scene.loader import load_scene

CLASS_NAMES = ("Error", "Exception", "NoneType", "object at 0x")


class _Unprintable(Exception):
    def __str__(self):
        raise UnicodeDecodeError("utf-8", b"\xff", 0, 1, "invalid start byte")


@pytest.mark.parametrize(
    "exc, said",
    [
        (AttributeError("'NoneType' object has no attribute 'write'"), "data of a form the reader does not expect"),
        (TypeError("unsupported operand type(s) for +: 'int' and 'str'"), "data of a form the reader does not expect"),
        (KeyError("vertices"), "data of a form the reader does not expect"),
        (KeyError("no such entity #42"), "no such entity #42"),  # a message, not a bare key
        (IndexError("list index out of range"), "data of a form the reader does not expect"),
        (OSError(28, "No space left on device"), "No space left on device"),
        (OSError("no errno"), "no errno"),
        (OSError(), "a system error"),
        (ValueError("could not read the header"), "could not read the header"),
        (UnicodeDecodeError("utf-8", b"\xff", 0, 1, "invalid start byte"), "text that is not valid in its encoding"),
        (RecursionError("maximum recursion depth exceeded"), "nested too deeply"),
        (MemoryError(), "out of memory"),
        (OverflowError("int too large to convert to float"), "a number out of range"),
        (np.linalg.LinAlgError("Singular matrix"), "a transform that cannot be inverted"),
        (
            UnidentifiedImageError("cannot identify image file <_io.BytesIO object at 0x7f3a2c>"),
            "cannot identify image file",
        ),
        (_Unprintable(), "a failure the library does not describe"),
        (ValueError(""), "a failure the library does not describe"),
        (ValueError("first line\nsecond"), "first line"),
    ],
)
def test_reason_is_in_the_users_terms(exc, said):
    assert reason(exc) == said
    assert not any(name in reason(exc) for name in CLASS_NAMES)


def test_damaged_archive_and_texture_messages_name_no_class(tmp_path):
    bad = tmp_path / "bad.3mf"
    bad.write_bytes(threemf_bad_deflate())
    with pytest.raises(RttaError) as caught:
        load_scene(bad)
    assert not any(name in str(caught.value) for name in CLASS_NAMES), caught.value
    textured = tmp_path / "textured.glb"
    textured.write_bytes(_textured(png()[:40]))
    scene = load_scene(textured)
    notes = [w for w in scene.warnings if "texture" in w]
    assert notes and not any(name in w for w in notes for name in CLASS_NAMES), scene.warnings
