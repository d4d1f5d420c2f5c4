"""Plain-text tables for the benchmarks and `rtta ldi --stats`."""


def print_table(columns, rows) -> None:
    """Columns right-aligned to their widest cell."""
    cells = [[str(c) for c in columns]] + [[str(v) for v in row] for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(columns))]
    for r in cells:
        print("  ".join(v.rjust(w) for v, w in zip(r, widths, strict=True)))
