# The seams of a mesh tile set imported into Blender: for each tile's right and bottom border,
# the vertices of both neighbours on that line and the largest distance from one to the nearest
# of the other's. Shared by tools/blender_check.py and tools/blender_addon_check.py.
import math


def tile_seams(tiles, size_m, top_m):
    """tiles: {(column, row): [world (x, y, z)]}; size_m: the tiles' size (mesh_tile_size_m);
    top_m: the terrain's north edge in y. Returns (border vertices, largest gap in metres)."""
    border, worst = 0, 0.0
    for (c, r), verts in tiles.items():
        for (dc, dr, axis, value) in ((1, 0, 0, (c + 1) * size_m), (0, 1, 1, top_m - (r + 1) * size_m)):
            other = tiles.get((c + dc, r + dr))
            if other is None:
                continue
            mine = [v for v in verts if abs(v[axis] - value) < 1e-3]
            theirs = [v for v in other if abs(v[axis] - value) < 1e-3]
            for v in mine + theirs:
                pool = theirs if v in mine else mine
                worst = max(worst, min(math.dist(v, u) for u in pool))
            border += len(mine)
    return border, worst
