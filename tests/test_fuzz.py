"""The fuzz targets of rtta's own parsers (tests/fuzz_targets.py), each run briefly and
deterministically: every seed of tests/fuzz_corpus/<target>/, then mutants of a fixed seed.
Each input gives a result or an RttaError, within LIMIT_S seconds and INPUT_MB of traced
memory. `python scripts/fuzz.py TARGET --seconds N` runs one coverage-guided (atheris); what
the fuzzing found is below, each as a regression test (docs/reliability.md)."""

from __future__ import annotations

import json
import time
import tracemalloc

import pytest
from fuzz_corpus_make import STEP_HEAD, STEP_TAIL
from fuzz_targets import INPUT_MB, LIMIT_S, LOADER_LIMIT_MB, TARGETS, mutants, run_one, seeds, warm

MUTANTS = {
    "obj": 60,
    "gltf": 60,
    "step": 200,
    "ifc": 60,
    "specs": 150,
    "views": 200,
    "cache": 200,
}  # a few seconds each


@pytest.fixture(autouse=True)
def _loader_limit(monkeypatch):
    """The fuzzing process's memory limit for the loader, for these tests only."""
    monkeypatch.setenv("RTTA_MEMORY_LIMIT_MB", LOADER_LIMIT_MB)


@pytest.mark.parametrize("target", list(TARGETS))
def test_target_keeps_its_contract(target):
    corpus = seeds(target)
    assert len(corpus) >= 4, "tests/fuzz_corpus is missing: python scripts/fuzz.py --corpus"
    warm(target)  # imports and first-use caches: not an input's time
    for k, data in enumerate([*corpus, *mutants(corpus, MUTANTS[target], seed=42)]):
        tracemalloc.start()
        start = time.perf_counter()
        try:
            run_one(target, data)
        except Exception as exc:  # the contract: a result or an RttaError
            pytest.fail(f"{target} input {k} ({data[:160]!r}): {type(exc).__name__}: {exc}")
        finally:
            seconds = time.perf_counter() - start
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
        assert seconds < LIMIT_S, f"{target} input {k} ({data[:160]!r}) took {seconds:.2f} s"
        assert peak < INPUT_MB * 2**20, f"{target} input {k} ({data[:160]!r}) allocated {peak / 2**20:.0f} MiB"


def test_mutants_are_deterministic_and_differ():
    corpus = seeds("specs")
    first, again = list(mutants(corpus, 20, seed=7)), list(mutants(corpus, 20, seed=7))
    assert first == again and len(set(first)) > 10 and not set(first) <= set(corpus)


# ---- findings, kept ---------------------------------------------------------------------
def _shared_levels(levels: int) -> str:
    """A product structure of `levels` assemblies, each using the next twice: 2^levels parts."""
    lines = ["#1=PRODUCT('leaf','leaf','',(#9));", "#2=PRODUCT_DEFINITION_FORMATION('','',#1);"]
    lines += [f"#{100 + i}=PRODUCT_DEFINITION('design','',#2,#8);" for i in range(levels + 1)]
    lines += [
        f"#{1000 + 2 * i + j}=NEXT_ASSEMBLY_USAGE_OCCURRENCE('u','','',#{100 + i},#{101 + i},$);"
        for i in range(levels)
        for j in range(2)
    ]
    return STEP_HEAD + "\n".join(lines) + "\n" + STEP_TAIL


def test_step_shared_product_structure_is_counted_not_unfolded():
    """Found while writing the step target: 24 levels took 5 s (2^24 names listed)."""
    from rtta.scene.readers import step

    start = time.perf_counter()
    text = _shared_levels(64)
    names = step._product_names(text, step._children(text))
    assert time.perf_counter() - start < 0.5
    assert names[(("leaf", 2**64),)] == "leaf" and names[(("leaf", 2),)] == "leaf"


def test_step_reference_that_is_not_a_number():
    """Found by the step target: '#' or '#x' where an entity reference stands raised ValueError."""
    from rtta.scene.readers import step

    text = _shared_levels(1).replace("#101,$);", "#,$);").replace("#100,", "#x1,", 1)
    assert step._product_names(text, step._children(text)) == {(("", 1),): "leaf"}  # one usage left, of no product
    one = _shared_levels(1)
    assert step._product_names(one, step._children(one)) == {(("leaf", 2),): "leaf"}


def test_ifc_aggregation_cycle_without_a_container():
    """Found by the ifc target: ifcopenshell's get_container recursed forever (RecursionError)
    up a cycle of aggregates none of which is in a spatial structure."""
    import ifcopenshell

    from rtta.scene.readers.ifc import tree_path

    model = ifcopenshell.file(schema="IFC4")
    a, b, c = (model.create_entity("IfcElementAssembly", Name=n) for n in "abc")
    model.create_entity("IfcRelAggregates", RelatingObject=a, RelatedObjects=[b])
    model.create_entity("IfcRelAggregates", RelatingObject=b, RelatedObjects=[a])
    model.create_entity("IfcRelNests", RelatingObject=a, RelatedObjects=[c])
    assert tree_path(c) == () and tree_path(a, {}) == ("b",) and tree_path(b, {}) == ("a",)
    storey = model.create_entity("IfcBuildingStorey", Name="1st")
    model.create_entity("IfcRelContainedInSpatialStructure", RelatingStructure=storey, RelatedElements=[b])
    assert tree_path(c) == ("1st",)  # the container of the nearest element above that has one


@pytest.mark.parametrize(
    "style",
    [
        {"outline_color": "1,0,0,1"},  # a string: its characters were floated (ValueError on ',')
        {"edge_color": ["red", 0, 0, 1]},
        {"edge_color": [1, 0, 0, 10**400]},  # OverflowError
        {"outline_color": 5},  # TypeError: not iterable
        {"desaturate": "0.5"},  # TypeError: str against float
        {"default_opacity": None},
        {"outline_width": [2]},
    ],
)
def test_style_values_that_are_no_numbers_are_one_error(style):
    """Found by the specs target: a colour or a style number of the wrong type raised
    ValueError, TypeError or OverflowError instead of naming the keyword."""
    from rtta.errors import RttaError
    from rtta.renderer.options import style_keywords

    with pytest.raises(RttaError, match=next(iter(style))):
        style_keywords(style)


def test_style_colours_as_before():
    from rtta.renderer.options import style_keywords

    assert style_keywords({"outline_color": ["1", 0.5, 0, 1]}) == {"outline_color": (1.0, 0.5, 0.0, 1.0)}
    assert style_keywords({"desaturate": 0.25, "outline_width": 3}) == {"desaturate": 0.25, "outline_width": 3}


@pytest.mark.parametrize(
    "text",
    [
        "[" * 100_000 + "]" * 100_000,
        '{"rtta_view": 1, "opacity": {"a": 1' + "0" * 400 + "}}",
        '[{"orbit": [1, 2, 1' + "0" * 400 + "]}]",
    ],
    ids=["nested", "400-digit opacity", "400-digit orbit"],
)
def test_view_and_cameras_files_of_deep_json_or_huge_integers(tmp_path, text):
    """Found by the views target: RecursionError from json, OverflowError from math.isfinite
    and float() of a 400-digit integer, in read_view and the dataset's parse_cameras."""
    from rtta.dataset.options import parse_cameras
    from rtta.errors import RttaError
    from rtta.renderer.view_file import read_view

    path = tmp_path / "view.json"
    path.write_text(text)
    for read in (read_view, parse_cameras):
        with pytest.raises(RttaError, match="view.json: "):
            read(path)


@pytest.mark.parametrize(
    "style, says",
    [
        ({"ao_radius": "context"}, "style.ao_radius must be a number"),
        ({"edge_width": None}, "style.edge_width must be an integer"),
        ({"halo": 2.5}, "style.halo must be an integer"),
        ({"order": 3}, "style.order must be a name or null"),
        ({"context_opacity": "x"}, "style.context_opacity must be a number or null"),
    ],
)
def test_view_file_style_values_of_the_wrong_kind(tmp_path, style, says):
    """Found by the views target: a name where a number belongs (ao_radius "context") reached
    make_style's comparisons and left as a TypeError."""
    from rtta.errors import RttaError
    from rtta.renderer.view_file import read_view

    path = tmp_path / "view.json"
    path.write_text(json.dumps({"rtta_view": 1, "style": style}))
    with pytest.raises(RttaError, match=f"view.json: {says}"):
        read_view(path)
    path.write_text(json.dumps({"rtta_view": 1, "style": {"ao_radius": 3, "order": None, "halo": 2}}))
    assert read_view(path).style["halo"] == 2


def test_a_name_pattern_of_thousands_of_brackets_is_refused_quickly():
    """Found by the specs target: fnmatch compiles a run of '[' in quadratic time (a 3,215
    character --focus took 1.2 s, 14 s traced); longer patterns are not globbed, and the
    message shows the first 200 characters."""
    from fuzz_targets import _scene

    from rtta.errors import RttaError
    from rtta.scene.select import resolve_names

    scene = _scene()
    start = time.perf_counter()
    with pytest.raises(RttaError, match=r"no object or group named '\[{200}\.\.\. \(65,536 characters\)'"):
        resolve_names(scene, ["[" * 65536], "--focus")
    assert time.perf_counter() - start < 0.5
    assert len(resolve_names(scene, ["b*"], "--focus")) == 2  # globs as before


def _dag_then_chain(levels: int, chain: int, broken: bool) -> bytes:
    """Nodes 0..levels-1 each with two children edges to the next (2^levels paths), then a chain
    of `chain` nodes to one mesh node; `broken`: the last DAG node's children misspelled."""
    from bad_gltf import box_doc, glb

    nodes = [{"children": [i + 1, i + 1]} for i in range(levels)]
    nodes += [{"children": [levels + k + 1]} for k in range(chain)] + [{"mesh": 0, "name": "leaf"}]
    if broken:
        nodes[levels - 1] = {"chilfren": [levels, levels]}
    return glb(*box_doc(nodes))


@pytest.mark.parametrize(
    "levels, chain, broken, says",
    [(40, 20, True, "no objects with triangle geometry"), (13, 100, False, "node paths to walk to its meshes")],
    ids=["no-mesh-below-2^40-paths", "8192-paths-of-100-nodes"],
)
def test_gltf_graph_walks_no_path_to_nothing_and_few_paths_in_all(tmp_path, levels, chain, broken, says):
    """Found by the gltf target (atheris): a 2^40-path DAG whose one path to the mesh was cut by
    a misspelled 'children' passed the mesh-path count (0 meshes) but the walk followed every
    path (minutes); subtrees without a mesh are not walked now, and the paths walked are bounded."""
    from rtta.errors import RttaError
    from rtta.scene.loader import load_scene

    path = tmp_path / "dag.glb"
    path.write_bytes(_dag_then_chain(levels, chain, broken))
    start = time.perf_counter()
    with pytest.raises(RttaError, match=says):
        load_scene(path)
    assert time.perf_counter() - start < 1.0


@pytest.mark.slow  # atheris instruments rtta first: about 10 s
def test_the_fuzzing_script_runs_a_target(tmp_path):
    """scripts/fuzz.py itself, end to end: its worker's command line once named the
    interpreter twice, and an hour of five targets ran 0 executions without a word."""
    import re
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parent.parent / "scripts" / "fuzz.py"
    args = [sys.executable, str(script), "specs", "--seconds", "6", "--work", str(tmp_path)]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=180, cwd=tmp_path)
    ran = re.search(r"specs: ([\d,]+) executions", proc.stdout)
    assert proc.returncode == 0 and ran and int(ran.group(1).replace(",", "")) > 100, proc.stdout + proc.stderr[-2000:]
