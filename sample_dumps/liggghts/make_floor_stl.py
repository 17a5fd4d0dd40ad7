"""Write an ASCII STL floor: a flat square at height z, split into an n x n grid of
squares, two triangles each (normals +z), so the wall dump's triangle ids vary.

Usage: python3 make_floor_stl.py OUT.stl HALF_WIDTH Z N
"""

import sys

out, half, z, n = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
step = 2 * half / n
lines = ["solid floor"]
for i in range(n):
    for j in range(n):
        x0, y0 = -half + i * step, -half + j * step
        x1, y1 = x0 + step, y0 + step
        for tri in (((x0, y0), (x1, y0), (x1, y1)), ((x0, y0), (x1, y1), (x0, y1))):
            lines += ["  facet normal 0 0 1", "    outer loop"]
            lines += [f"      vertex {x:.6f} {y:.6f} {z:.6f}" for x, y in tri]
            lines += ["    endloop", "  endfacet"]
lines.append("endsolid floor")
open(out, "w").write("\n".join(lines) + "\n")
