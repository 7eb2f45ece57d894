#!/usr/bin/env python3
"""The ski-track picture of docs/models/skiers.md from a bake of docs/pictures/ski_tracks_tyrol.toml: the shaded
snow surface with the ski-track texture cut into it, the 500 m x 500 m window holding the most
track texels. Usage: ski_tracks.py BAKE_DIR OUT.png (needs python3-openimageio, python3-numpy)."""
import json
import sys

import numpy as np
import OpenImageIO as oiio


def read(path):
    img = oiio.ImageInput.open(path)
    if img is None:
        sys.exit(f"ski_tracks.py: cannot read {path}: {oiio.geterror()}")
    pixels = img.read_image(oiio.FLOAT)
    img.close()
    return np.asarray(pixels)[:, :, 0]


def main():
    bake, out = sys.argv[1], sys.argv[2]
    manifest = json.load(open(f"{bake}/manifest.json"))
    surface, tracks = read(f"{bake}/surface.exr"), read(f"{bake}/ski_tracks.exr")
    factor = tracks.shape[1] // surface.shape[1]
    cell = float(manifest["terrain"]["cell_size_x_m"])
    # Hillshade of the surface from the north-west, 45 degrees up.
    gy, gx = np.gradient(np.nan_to_num(surface, nan=np.nanmin(surface)), cell)
    nx, ny, nz = -gx, gy, np.ones_like(gx)
    norm = np.sqrt(nx * nx + ny * ny + nz * nz)
    light = np.array([-1.0, 1.0, np.sqrt(2.0)]) / 2.0
    shade = np.clip((nx * light[0] + ny * light[1] + nz * light[2]) / norm, 0.0, 1.0)
    shade = np.kron(shade, np.ones((factor, factor)))  # to the texture's texels
    # The window (100 cells a side at 5 m) with the most track texels.
    win = int(round(500.0 / cell)) * factor
    marked = (tracks > 0.005).astype(np.float64)
    s = marked.cumsum(0).cumsum(1)
    s = np.pad(s, ((1, 0), (1, 0)))
    counts = s[win:, win:] - s[:-win, win:] - s[win:, :-win] + s[:-win, :-win]
    y0, x0 = np.unravel_index(np.argmax(counts[::factor, ::factor]), counts[::factor, ::factor].shape)
    y0, x0 = y0 * factor, x0 * factor
    sh = shade[y0:y0 + win, x0:x0 + win]
    tr = tracks[y0:y0 + win, x0:x0 + win] / max(1e-6, float(tracks.max()))
    snow = np.array([0.93, 0.95, 1.0])
    groove = np.array([0.30, 0.37, 0.50])
    base = (0.55 + 0.45 * sh)[:, :, None] * snow
    rgb = base * (1 - tr[:, :, None]) + groove * tr[:, :, None]
    rgb8 = (np.clip(rgb, 0, 1) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)
    o = oiio.ImageOutput.create(out)
    o.open(out, oiio.ImageSpec(win, win, 3, oiio.UINT8))
    o.write_image(rgb8)
    o.close()
    print(f"ski_tracks.py: {out}: window at texel ({x0}, {y0}), {int(counts[y0, x0])} track texels")


main()
