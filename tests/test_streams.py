"""Standard streams the run cannot use (issue 42): stdout or stderr closed (`>&-`, `2>&-`),
stdout or stderr full (/dev/full), stdin closed. The run says what happened in one line
where it can, its exit status tells where it cannot, and no message names a Python class."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from bad_gltf import box_doc, glb

from rtta.cli.guard import run_command, unexpected
from rtta.errors import RttaError

RTTA = str(Path(sys.executable).with_name("rtta"))
CLASS_NAMES = ("Error:", "Exception", "NoneType", "Traceback", "AttributeError", "LinAlgError")


@pytest.fixture(scope="module")
def box(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("streams") / "box.glb"
    path.write_bytes(glb(*box_doc()))
    return path


def _rtta(args, close=(), stdout=subprocess.PIPE, stderr=subprocess.PIPE) -> subprocess.CompletedProcess:
    def closing():  # in the child, after the pipes are in place
        for fd in close:
            os.close(fd)

    return subprocess.run(
        [RTTA, *map(str, args)], stdout=stdout, stderr=stderr, preexec_fn=closing, timeout=120, check=False
    )


def _clean(text: bytes) -> str:
    out = text.decode()
    assert not any(name in out for name in CLASS_NAMES), out
    return out


def test_closed_stdout_is_one_line(box):
    proc = _rtta(["info", box], close=[1])
    err = _clean(proc.stderr)
    assert proc.returncode == 2 and err == "rtta: error: cannot write to standard output (it is closed)\n", err


def test_closed_stderr_keeps_the_output_and_the_status(box):
    good = _rtta(["info", box], close=[2])
    assert good.returncode == 0 and b"box.glb: 1 objects" in good.stdout and b"rtta:" not in good.stdout
    bad = _rtta(["info", box.with_name("missing.glb")], close=[2])
    assert bad.returncode == 2 and bad.stdout == b""  # the error never falls back to stdout
    both = _rtta(["info", box], close=[1, 2])
    assert both.returncode == 2


def test_full_stdout_and_full_stderr(box):
    with open("/dev/full", "wb") as full:
        proc = _rtta(["info", box], stdout=full)
        err = _clean(proc.stderr)
        assert proc.returncode == 2 and err.startswith("rtta: error: cannot write to standard output (No space")
        bad = _rtta(["info", box.with_name("missing.glb")], stderr=full)
    assert bad.returncode == 2 and bad.stdout == b""


def test_closed_stdin_is_no_matter(box):
    proc = _rtta(["info", box], close=[0])
    assert proc.returncode == 0 and b"1 objects" in proc.stdout and proc.stderr == b""


def test_closed_descriptors_are_held_so_no_file_takes_them(tmp_path):
    code = (
        "import os, sys; from rtta.cli.guard import hold_closed_streams; hold_closed_streams(); "
        "fd = os.open('out.txt', os.O_WRONLY | os.O_CREAT); os.write(fd, str(fd).encode()); sys.stderr.write('x')"
    )
    for fd in (0, 1, 2):
        proc = subprocess.run(
            [sys.executable, "-c", code],
            cwd=tmp_path,
            capture_output=True,
            preexec_fn=lambda fd=fd: os.close(fd),
            timeout=60,
        )
        assert proc.returncode == 0 and int((tmp_path / "out.txt").read_text()) > 2, (fd, proc.stderr)
        assert proc.stdout == b"", proc.stdout  # with stderr closed, its text went to /dev/null, not stdout


@pytest.mark.parametrize(
    "exc, said",
    [
        (np.linalg.LinAlgError("Singular matrix"), "a matrix computation on it failed"),
        (AttributeError("'NoneType' object has no attribute 'write'"), "rtta met a case it does not handle"),
        (KeyError("accessors"), "rtta met a case it does not handle"),
        (RecursionError("maximum recursion depth exceeded"), "nested too deeply"),
        (OverflowError("int too large to convert to float"), "too large"),
        (UnicodeDecodeError("utf-8", b"\xff", 0, 1, "invalid start byte"), "not valid in its encoding"),
    ],
)
def test_unexpected_failures_are_said_in_the_users_terms(exc, said, capsys, monkeypatch):
    monkeypatch.delenv("RTTA_DEBUG", raising=False)

    def handler(args):
        raise exc

    assert run_command(handler, type("Args", (), {"scene": "model.glb"})()) == 2
    err = capsys.readouterr().err
    assert err.startswith("rtta: error: model.glb: cannot process this input: ") and said in err, err
    assert err.count("\n") == 1 and type(exc).__name__ not in err and str(exc) not in err, err
    assert unexpected(exc) in err


def test_an_oserror_without_a_reason_names_no_class(capsys):
    def handler(args):
        raise OSError("no errno")

    assert run_command(handler, type("Args", (), {"scene": "model.glb"})()) == 2
    err = capsys.readouterr().err
    assert err == "rtta: error: model.glb: the system refused to read or write it\n", err


def test_rtta_error_is_unchanged(capsys):
    def handler(args):
        raise RttaError("a reason", "model.glb")

    assert run_command(handler, type("Args", (), {})()) == 2
    assert capsys.readouterr().err == "rtta: error: model.glb: a reason\n"


def test_a_command_sees_stdout_as_a_stream(capsys):
    """Inside a command, sys.stdout is guarded (its write errors are one line) but still a
    stream: a library asking its descriptor or encoding (a native reader silencing fd 1) gets
    them. The guard's __getattr__ sat in another function and did nothing."""
    seen = {}

    def handler(args) -> int:
        seen["encoding"], seen["tty"] = sys.stdout.encoding, sys.stdout.isatty()
        seen["fileno"] = sys.stdout.fileno
        return 0

    assert run_command(handler, None) == 0  # type: ignore[arg-type]
    assert seen["encoding"] and seen["tty"] in (True, False) and callable(seen["fileno"])
