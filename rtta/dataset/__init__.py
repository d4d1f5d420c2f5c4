"""Dataset layer: amodal datasets of assemblies (`rtta dataset`), a product feature on the renderer.

`options` (settings, cameras, shards, the output folder), `view` (one view from one capture,
or the RTT baseline through `alone`), `run` (workers, resuming, the writer thread),
`objects` (categories), `cluster` (shards on Dask), `coco` (COCO RLE encoding, assembly and
merge). Imports the renderer layer and below; imported by the bench layer and the CLI.
"""
