"""Bench layer: measurements built on the renderer and the dataset generator, not part of a frame.

The benchmarks behind `rtta bench` (`render`: capture, packing, composite; `scale`, `ldi`,
`material`, `formats`, `reliability_table`, `dataset`), the reliability sweep and soak
(`reliability`), image comparison with the tests' tolerances (`compare`), and `rtta bench
report` (`report*`: docs/performance/report.md's block and the plots in docs/bench/; plotting needs the
`report` extra). Imports the dataset layer and below; nothing imports it but the CLI.
"""
