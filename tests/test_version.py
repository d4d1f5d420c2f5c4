"""The version is written once, in rtta/__init__.py: pyproject.toml reads it from there
(setuptools' dynamic version), so the installed metadata says the same."""

from __future__ import annotations

import importlib.metadata
import tomllib
from pathlib import Path

import rtta


def test_the_installed_version_is_rtta_version():
    assert rtta.__version__ == importlib.metadata.version("rtta")


def test_pyproject_reads_the_version_from_rtta():
    project = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    assert "version" not in project["project"] and "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "rtta.__version__"}
