"""An amodal dataset rendered on a Dask cluster, and its masks drawn.

`rtta.dataset.cluster.run_shards` runs `rtta dataset ARGV --shard I/N` as N tasks of a
dask.distributed client, each in a process (and EGL context) of its own, all writing into
one folder; `rtta dataset merge` joins their COCO annotations. Here a LocalCluster of two
workers renders four views of the demo; each is drawn with every part's visible mask tinted
and its AMODAL mask outlined, hidden parts included (needs the `dataset` extra and dask).

    python examples/dask_dataset.py [OUT_DIR]    # writes OUT_DIR/dask_dataset.png and OUT_DIR/dataset/
"""

import json
import sys
from pathlib import Path

import numpy as np
from dask.distributed import Client, LocalCluster
from PIL import Image
from pycocotools import mask as rle
from scipy import ndimage

from rtta.cli.main import main as rtta_cli
from rtta.dataset.cluster import run_shards

# `rtta dataset` options (no scene given: the demo), as on the command line
ARGV = "--views 4 --size 320x240 --seed 3 --elevation 15,45 --distance 1.7,2.1 --fov 45".split()


def main(out: Path) -> Path:
    data = (out / "dataset").absolute()  # one folder every worker can see (a shared one on a real cluster)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            codes = run_shards(client, [*ARGV, "--out", str(data)], shards=2)  # [(exit code, stderr tail)]
    assert all(code == 0 for code, _ in codes), codes
    rtta_cli(["dataset", "merge", str(data), "--out", str(data / "annotations.json")])
    coco = json.loads((data / "annotations.json").read_text())
    palette = np.random.default_rng(0).integers(60, 255, (len(coco["categories"]) + 1, 3))
    tiles = []
    for image in coco["images"]:
        rgb = np.asarray(Image.open(data / image["file_name"]).convert("RGB"), float) * 0.6 + 40
        for ann in (a for a in coco["annotations"] if a["image_id"] == image["id"]):
            colour = palette[ann["category_id"]]
            visible, amodal = (rle.decode(ann[k]).astype(bool) for k in ("segmentation", "amodal_segmentation"))
            rgb[visible] = 0.5 * rgb[visible] + 0.5 * colour
            rgb[amodal & ~ndimage.binary_erosion(amodal)] = colour  # the outline of the whole part
        tiles.append(rgb.astype(np.uint8))
    sheet = np.concatenate([np.concatenate(tiles[:2], axis=1), np.concatenate(tiles[2:4], axis=1)], axis=0)
    print(f"{len(coco['images'])} views, {len(coco['annotations'])} annotations")
    Image.fromarray(sheet).save(out / "dask_dataset.png")
    return out / "dask_dataset.png"


if __name__ == "__main__":  # the guard matters: the cluster's worker processes import this file
    out = Path(sys.argv[1] if sys.argv[1:] else "out/examples")
    out.mkdir(parents=True, exist_ok=True)
    print("wrote", main(out))
