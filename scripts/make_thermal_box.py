#!/usr/bin/env python3
"""Writes data/thermal_box/thermal_box.stl: a 1000 x 1000 x 500 mm box (ASCII STL, one
`solid` per surface: heater (floor), cold_plate (ceiling), walls (four sides)) with every
facet wound counter-clockwise seen from inside (front normals point into the box)."""
import pathlib

L, W, H = 1000.0, 1000.0, 500.0
# quads, listed clockwise seen from inside (reversed below: counter-clockwise about the
# inward front normal)
faces = {
    "heater": [[(0, 0, 0), (0, W, 0), (L, W, 0), (L, 0, 0)]],
    "cold_plate": [[(0, 0, H), (L, 0, H), (L, W, H), (0, W, H)]],
    "walls": [
        [(0, 0, 0), (L, 0, 0), (L, 0, H), (0, 0, H)],
        [(L, 0, 0), (L, W, 0), (L, W, H), (L, 0, H)],
        [(L, W, 0), (0, W, 0), (0, W, H), (L, W, H)],
        [(0, W, 0), (0, 0, 0), (0, 0, H), (0, W, H)],
    ],
}


def normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    s = sum(x * x for x in n) ** 0.5
    return [x / s for x in n]


out = []
for name, quads in faces.items():
    out.append(f"solid {name}")
    for q in (list(reversed(q)) for q in quads):
        for tri in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
            n = normal(*tri)
            out.append("  facet normal {:g} {:g} {:g}".format(*n))
            out.append("    outer loop")
            for p in tri:
                out.append("      vertex {:g} {:g} {:g}".format(*p))
            out.append("    endloop")
            out.append("  endfacet")
    out.append(f"endsolid {name}")
path = pathlib.Path(__file__).resolve().parent.parent / "data" / "thermal_box" / "thermal_box.stl"
path.write_text("\n".join(out) + "\n")
print("wrote", path)
