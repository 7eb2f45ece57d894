#!/usr/bin/env python3
"""Compares the float layers of two bakes written with the "r32" encoding (raw little-endian
float32, no header): for each layer named, the relative L1 difference (sum |b - a| / sum |a|),
the largest absolute difference and the cells that differ. Prints a Markdown table.

    tools/compare-layers.py OLD_DIR NEW_DIR depth powder ...
"""
import array
import os
import sys


def read(path):
    values = array.array("f")
    with open(path, "rb") as f:
        values.frombytes(f.read())
    if sys.byteorder != "little":
        values.byteswap()
    return values


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    old_dir, new_dir, layers = argv[1], argv[2], argv[3:]
    print("| layer | cells | relative L1 | largest difference | cells that differ |")
    print("|---|---|---|---|---|")
    for layer in layers:
        a, b = (read(os.path.join(d, layer + ".r32")) for d in (old_dir, new_dir))
        if len(a) != len(b):
            sys.exit(f"{layer}: {len(a)} cells in {old_dir}, {len(b)} in {new_dir}")
        total = sum(abs(x) for x in a)
        diff = [abs(y - x) for x, y in zip(a, b)]
        rel = sum(diff) / total if total > 0 else float("nan")
        print(f"| {layer} | {len(a)} | {rel:.3e} | {max(diff):.3e} | {sum(1 for d in diff if d != 0)} |")


if __name__ == "__main__":
    main(sys.argv)
