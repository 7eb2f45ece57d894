#!/usr/bin/env python3
"""The snow-on-a-mesh picture of docs/models/snow-on-meshes.md. `mesh_snow_table.py obj OUT.obj` writes the scene's mesh (a
3 m x 3 m ground inside a curb, a table whose top overhangs on four legs, a 35 degree wedge and a
stepped block: our own geometry, z up); `mesh_snow_table.py render MESH.obj BAKE_DIR OUT.png` draws the
mesh and the baked snow body (BAKE_DIR/snow_body.obj, y-up as the OBJ writer writes it) in an
orthographic view with a z-buffer (Debian's python3 with numpy and OpenImageIO)."""
import math
import sys

import numpy as np


def box(v, f, x0, y0, z0, x1, y1, z1):
    b = len(v) + 1
    v += [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0), (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    # outward, counter-clockwise seen from outside
    for q in [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]:
        f += [(b + q[0], b + q[1], b + q[2]), (b + q[0], b + q[2], b + q[3])]


def write_obj(path):
    v, f = [], []
    v += [(0, 0, 0), (3, 0, 0), (3, 3, 0), (0, 3, 0)]
    f += [(1, 2, 3), (1, 3, 4)]
    box(v, f, 0.4, 1.2, 0.70, 1.8, 2.2, 0.76)  # table top
    for x, y in [(0.5, 1.3), (1.62, 1.3), (0.5, 2.02), (1.62, 2.02)]:
        box(v, f, x, y, 0.0, x + 0.08, y + 0.08, 0.70)  # legs
    # a wedge rising east at 35 degrees, closed
    h = 0.6 * math.tan(math.radians(35))
    b = len(v) + 1
    v += [(2.1, 0.3, 0), (2.7, 0.3, 0), (2.7, 1.5, 0), (2.1, 1.5, 0), (2.7, 0.3, h), (2.7, 1.5, h)]
    f += [(b, b + 1, b + 4), (b + 3, b + 5, b + 2), (b, b + 4, b + 5), (b, b + 5, b + 3), (b + 1, b + 2, b + 5), (b + 1, b + 5, b + 4)]
    for x0, y0, x1, y1 in [(0, 0, 3, 0.05), (0, 2.95, 3, 3), (0, 0.05, 0.05, 2.95), (2.95, 0.05, 3, 2.95)]:
        box(v, f, x0, y0, 0.0, x1, y1, 0.45)  # a curb round the ground: its snow stays level
    box(v, f, 0.4, 0.3, 0.0, 1.2, 0.8, 0.3)  # a low block
    box(v, f, 0.6, 0.4, 0.3, 1.0, 0.7, 0.55)  # and a step on it
    with open(path, "w") as o:
        for p in v:
            o.write("v %g %g %g\n" % p)
        for t in f:
            o.write("f %d %d %d\n" % t)


def read_obj(path, y_up):
    vs, fs = [], []
    for line in open(path):
        if line.startswith("v "):
            x, y, z = map(float, line.split()[1:4])
            vs.append((x, -z, y) if y_up else (x, y, z))
        elif line.startswith("f "):
            idx = [int(p.split("/")[0]) - 1 for p in line.split()[1:]]
            for k in range(1, len(idx) - 1):
                fs.append((idx[0], idx[k], idx[k + 1]))
    return np.array(vs), np.array(fs)


def render(mesh_obj, bake, out):
    import OpenImageIO as oiio
    W, H = 1200, 800
    az, el = math.radians(215), math.radians(32)
    fwd = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), -math.sin(el)])  # view direction
    right = np.cross(fwd, [0, 0, 1]); right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    light = np.array([-0.4, -0.6, 0.7]); light /= np.linalg.norm(light)
    parts = [(read_obj(mesh_obj, False), np.array([0.55, 0.50, 0.45])), (read_obj(bake + "/snow_body.obj", True), np.array([0.95, 0.97, 1.0]))]
    allv = np.vstack([p[0][0] for p in parts])
    centre = allv.mean(axis=0)
    proj = lambda P: np.stack([(P - centre) @ right, (P - centre) @ up, (P - centre) @ fwd], axis=1)
    uv = proj(allv)
    scale = 0.92 * min(W / (uv[:, 0].ptp()), H / (uv[:, 1].ptp()))
    zbuf = np.full((H, W), np.inf)
    img = np.ones((H, W, 3)) * np.array([0.80, 0.85, 0.92])
    for (V, F), colour in parts:
        P = proj(V)
        sx = W / 2 + P[:, 0] * scale
        sy = H / 2 - P[:, 1] * scale
        for t in F:
            a, b, c = V[t[0]], V[t[1]], V[t[2]]
            n = np.cross(b - a, c - a)
            ln = np.linalg.norm(n)
            if ln == 0:
                continue
            n /= ln
            shade = colour * (0.35 + 0.65 * abs(n @ light))
            xs, ys, zs = sx[list(t)], sy[list(t)], P[list(t), 2]
            x0, x1 = max(int(xs.min()), 0), min(int(xs.max()) + 1, W - 1)
            y0, y1 = max(int(ys.min()), 0), min(int(ys.max()) + 1, H - 1)
            if x1 < x0 or y1 < y0:
                continue
            gx, gy = np.meshgrid(np.arange(x0, x1 + 1) + 0.5, np.arange(y0, y1 + 1) + 0.5)
            d = (ys[1] - ys[2]) * (xs[0] - xs[2]) + (xs[2] - xs[1]) * (ys[0] - ys[2])
            if abs(d) < 1e-12:
                continue
            l0 = ((ys[1] - ys[2]) * (gx - xs[2]) + (xs[2] - xs[1]) * (gy - ys[2])) / d
            l1 = ((ys[2] - ys[0]) * (gx - xs[2]) + (xs[0] - xs[2]) * (gy - ys[2])) / d
            l2 = 1 - l0 - l1
            inside = (l0 >= -1e-6) & (l1 >= -1e-6) & (l2 >= -1e-6)
            z = l0 * zs[0] + l1 * zs[1] + l2 * zs[2]
            sub = zbuf[y0:y1 + 1, x0:x1 + 1]
            m = inside & (z < sub)
            sub[m] = z[m]
            img[y0:y1 + 1, x0:x1 + 1][m] = shade
    rgb8 = (np.clip(img, 0, 1) ** (1 / 2.2) * 255 + 0.5).astype(np.uint8)
    o = oiio.ImageOutput.create(out)
    o.open(out, oiio.ImageSpec(W, H, 3, oiio.UINT8))
    o.write_image(rgb8)
    o.close()
    print("mesh_snow_table.py: " + out)


if sys.argv[1] == "obj":
    write_obj(sys.argv[2])
else:
    render(sys.argv[2], sys.argv[3], sys.argv[4])
