"""Running the views of `rtta dataset`: in this process, or in K spawned processes with one
EGL context each, with a progress bar. A scene that cannot be read is said in one line and
stops the run, or with keep-going is skipped while the others go on."""

from __future__ import annotations

import multiprocessing
import signal
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from ..errors import RttaError, printable
from ..outputs import atomic_write
from ..scene.files import regular_file
from . import coco
from . import options as ds
from .objects import object_meta
from .options import Options, Run, complete, part_path, view_dir
from .view import MAX_PNG_ID, annotate, camera_entry, depth_scale, render_rtta, view_files, write_view


class Worker:
    """Renders views, one scene loaded at a time (the last one is kept for the next chunk)."""

    def __init__(self, s: dict, out: Path, scenes: dict | None = None, cache: bool = True) -> None:
        self.s, self.out, self.cache = s, Path(out), cache
        self.given = scenes or {}  # in-memory scenes by their SCENE argument (library, tests)
        self.index: int | None = None
        self.renderer = None
        self.meta: list[dict] = []
        self.failed: dict[int, str] = {}
        self.writer = Writer()

    def _open(self, index: int) -> None:
        """Load scene `index`, write its part (objects and categories) and make its renderer."""
        if self.index == index:
            return
        from ..gl.context import shared_context
        from ..renderer.placing import make_staging
        from ..renderer.renderer import Renderer
        from ..scene.loader import load_scene

        self.close()
        sc = self.s["scenes"][index]
        scene = self.given.get(sc["file"]) or load_scene(
            sc["file"], smooth_angle=self.s["smooth_angle"], smooth=self.s["smooth"], cache=self.cache
        )
        for note in scene.warnings:
            print(f"rtta: warning: {printable(scene.source)}: {printable(note)}", file=sys.stderr)
        self.meta = object_meta(scene, self.s["category_by"])
        part = {"key": sc["key"], "file": sc["file"], "objects": [{"id": i, **m} for i, m in enumerate(self.meta)]}
        path = part_path(self.out, sc["key"])
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(path, lambda tmp: Path(tmp).write_text(coco.dumps(part), encoding="utf-8"))
        self.renderer = Renderer(shared_context(), scene)
        self.renderer.staging = make_staging(
            self.s.get("sections", []), self.s.get("caps", "solid"), "all", self.s.get("explode", 0.0)
        )
        self.renderer.staging.framed(scene)  # a plane removing every part: this scene fails here
        self.index = index

    def view(self, index: int, view: int) -> int:
        """Render, annotate and write one view; its part last (the view is then complete)."""
        return produce_view(self.renderer, self.s, self.meta, (index, view), self.out, writer=self.writer)

    def run(self, chunk: list[tuple[int, int]]) -> list[tuple]:
        """("done", scene, view, annotations) per view, or one ("error", scene, message)."""
        out = []
        for index, view in chunk:
            if index in self.failed:
                return [("error", index, self.failed[index])]
            try:
                self._open(index)
            except RttaError as exc:
                self.failed[index] = str(exc)
                return [("error", index, str(exc))]
            _clean_stale(self.out, self.s["scenes"][index]["key"], view)
            out.append(("done", index, view, self.view(index, view)))
        return out

    def close(self) -> None:
        """Wait for the views being written, and free the scene's GPU resources."""
        try:
            self.writer.wait()
        finally:
            if self.renderer is not None:
                self.renderer.release()
            self.renderer, self.index = None, None


class Writer:
    """Writes views on one background thread while the next view renders (PNG and zlib work
    release the GIL). At most one view waits to be written, so memory stays one view's worth;
    a failed write is raised at the next submit or at close. background=False writes at once."""

    def __init__(self, background: bool = True) -> None:
        self._pool = ThreadPoolExecutor(1, thread_name_prefix="rtta-writer") if background else None
        self._pending = None

    def submit(self, job) -> None:
        if self._pool is None:
            job()
            return
        self.wait()
        self._pending = self._pool.submit(job)

    def wait(self) -> None:
        if self._pending is not None:
            done, self._pending = self._pending, None
            done.result()

    def close(self) -> None:
        try:
            self.wait()
        finally:
            if self._pool is not None:
                self._pool.shutdown(wait=True)


def produce_view(
    renderer,
    s: dict,
    meta: list[dict],
    item: tuple[int, int],
    out: Path,
    render=render_rtta,
    times: dict | None = None,
    writer: Writer | None = None,
) -> int:
    """One view of scene item[0] (loaded in `renderer`) into `out`: rendered by `render`
    (render_rtta, or the benchmark's render_rtt), annotated, then its folder and its part
    written by `writer` (at once without one). Returns the number of annotations; `times`
    gets render/annotate/write seconds added."""
    index, view = item
    key = s["scenes"][index]["key"]
    scene = renderer.scene
    size = tuple(s["size"])
    framed = renderer.staging.framed(scene)  # exploded: the cameras frame the moved parts
    camera, how = ds.camera_for(s, key, view, framed.center, framed.radius, scene)
    renderer.hidden = set(ds.hidden_ids(s, scene))  # a saved view's hidden parts: not drawn nor annotated
    t0 = time.perf_counter()
    result = render(renderer, camera, size, appearance=s["appearance"])
    t1 = time.perf_counter()
    folder = view_dir(key, view)
    iid = ds.image_id(s, item)
    notes = annotate(result, meta, iid, s["min_visible"], folder if s["appearance"] else None)
    cam = dict(camera_entry(renderer, camera, size), **how)
    big = scene.count > MAX_PNG_ID
    image = {
        "id": iid,
        **view_files(folder, s["depth"], big),
        "width": size[0],
        "height": size[1],
        "scene": key,
        "scene_file": s["scenes"][index]["file"],
        "view_index": view,
        "camera": cam,
    }
    if s["depth"] == "png":
        image["depth_scale"] = depth_scale(cam)
    _add(times, "render", t1 - t0)
    _add(times, "annotate", time.perf_counter() - t1)

    def write() -> None:
        t2 = time.perf_counter()
        try:
            write_view(result, out / folder, s["depth"], depth_scale(cam), big, {a["object_id"] for a in notes})
            part = part_path(out, key, view)
            part.parent.mkdir(parents=True, exist_ok=True)
            doc = {"image": image, "annotations": notes}
            atomic_write(part, lambda tmp: Path(tmp).write_text(coco.dumps(doc), encoding="utf-8"))
        except OSError as exc:
            raise RttaError(f"cannot write ({exc.strerror or exc})", exc.filename or out / folder) from None
        _add(times, "write", time.perf_counter() - t2)

    (writer or Writer(background=False)).submit(write)
    return len(notes)


def _add(times: dict | None, stage: str, seconds: float) -> None:
    if times is not None:
        times[stage] = times.get(stage, 0.0) + seconds


def _clean_stale(out: Path, key: str, view: int) -> None:
    """Temporaries a killed run left for this view: a folder beside its folder, a file beside
    its part (only this shard writes this view, so nothing else is writing them)."""
    import shutil

    folder, part = out / view_dir(key, view), part_path(out, key, view)
    for tmp in [*folder.parent.glob(f".{folder.name}.*"), *part.parent.glob(f".{part.name}.*")]:
        if tmp.is_dir():
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            tmp.unlink(missing_ok=True)


def chunks(todo: list[tuple[int, int]], size: int) -> list[list[tuple[int, int]]]:
    """Runs of at most `size` consecutive views of one scene."""
    out: list[list[tuple[int, int]]] = []
    for item in todo:
        if out and len(out[-1]) < size and out[-1][-1][0] == item[0]:
            out[-1].append(item)
        else:
            out.append([item])
    return out


_worker: Worker | None = None


def _init(s: dict, out: str, cache: bool = True) -> None:
    global _worker
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl+C
    signal.signal(signal.SIGTERM, _exit)  # temporaries are removed on the way out
    _worker = Worker(s, Path(out), cache=cache)


def _exit(*_):
    raise SystemExit(143)


def _task(chunk):
    worker = _worker
    assert worker is not None, "the pool's initializer made it"
    try:
        return worker.run(chunk)
    finally:
        worker.writer.wait()  # the chunk's views are on disk before it is reported


def execute(s: dict, how: Run, todo: list[tuple[int, int]], scenes: dict | None = None) -> set[int]:
    """Render the views in `todo`; returns the scenes that could not be read. `scenes`:
    in-memory scenes by SCENE argument (this process only, so not with workers > 1)."""
    failed: set[int] = set()
    if not todo:
        return failed
    bar = _bar(len(todo), how.progress)
    workers = max(1, min(how.workers, len(todo)))
    try:
        if workers == 1:
            worker = Worker(s, how.out, scenes, how.cache)
            try:
                for chunk in chunks(todo, 1):
                    if chunk[0][0] in failed:
                        continue
                    if not _collect(worker.run(chunk), failed, how, bar):
                        break
            finally:
                worker.close()
        else:
            if scenes:
                raise ValueError("in-memory scenes are rendered in this process: workers must be 1")
            size = max(1, min(8, len(todo) // (workers * 4)))
            pool = multiprocessing.get_context("spawn").Pool(workers, _init, (s, str(how.out), how.cache))
            try:
                for results in pool.imap_unordered(_task, chunks(todo, size)):
                    if not _collect(results, failed, how, bar):
                        break
            finally:
                pool.terminate()
                pool.join()
    finally:
        bar.close()
    return failed


def _collect(results: list[tuple], failed: set[int], how: Run, bar) -> bool:
    """Count finished views; say a scene's error once. False: stop the run."""
    for r in results:
        if r[0] == "done":
            bar.update(1)
        elif r[1] not in failed:
            failed.add(r[1])
            bar.clear()
            print(
                f"rtta: error: {printable(r[2])}" + ("" if how.keep_going else " (stopped; --keep-going skips it)"),
                file=sys.stderr,
            )
            if not how.keep_going:
                return False
    return True


def _bar(total: int, progress: bool | None):
    try:
        from tqdm import tqdm
    except ImportError:
        raise RttaError("tqdm is needed for rtta dataset: pip install 'rtta[dataset]'") from None
    return tqdm(
        total=total,
        unit="view",
        disable=None if progress is None else not progress,
        file=sys.stderr,
        dynamic_ncols=True,
    )


def run(opts: Options, how: Run, scenes: dict | None = None) -> int:
    """Render the shard's missing views, then assemble its annotations; 0, or 2 when a scene
    could not be read (after the others with keep_going, at once without)."""
    paths = ds.expand_scenes(opts.scenes)
    if not how.keep_going:  # a scene that cannot be read stops the run: before anything is written
        for path in paths:
            if path not in (scenes or {}):
                regular_file(Path(path), "scene file")
    s = ds.settings(opts, paths)
    ds.prepare_out(how.out, s, ds.annotations_name(how.shard))
    items = ds.items_of(s, how.shard)
    keys = [sc["key"] for sc in s["scenes"]]
    todo = [it for it in items if not complete(how.out, keys[it[0]], it[1])]
    t0 = time.perf_counter()
    failed = execute(s, how, todo, scenes)
    elapsed = time.perf_counter() - t0
    if failed and not how.keep_going:
        return 2
    target, doc = ds.assemble(how.out, s, items, ds.annotations_name(how.shard))
    rendered = len(todo) - sum(1 for it in todo if it[0] in failed)
    rate = f", {rendered / elapsed:.2f} views/s" if rendered and elapsed > 0 else ""
    skipped = f", {len(failed)} scene(s) skipped" if failed else ""
    print(
        f"wrote {target}: {len(doc['images'])} images, {len(doc['annotations'])} annotations "
        f"({rendered} views rendered, {len(items) - len(todo)} already complete{skipped}{rate})"
    )
    return 2 if failed else 0
