"""Tools layer: measurements built on the renderer, not part of a frame.

The benchmarks behind `rtta bench` (capture, packing, composite, ldi, material, reliability,
dataset), `rtta dataset` (amodal COCO datasets: dataset*.py, coco.py),
the reliability sweep and soak, image comparison with the tests' tolerances, memory
figures, and `rtta bench report` (BENCHMARKS.md and the plots in docs/bench/; plotting needs
the `report` extra). Imports the renderer layer and below; nothing imports it but the CLI.
"""
