#!/usr/bin/env python3
"""Writes heat_sink.stl: a stand-in for a CAD-exported extruded heat sink (binary STL, metres).

A 100 x 80 x 6 mm base plate carrying 24 straight fins (1.2 mm thick, 35 mm tall, 100 mm
long) with round tips, tessellated the way CAD exporters do it: each round tip is 38 facets
100 mm long and ~0.05 mm wide (aspect ~2000), each fin end cap a fan of long thin triangles,
the base top one 2-triangle strip per gap, T-junctions where the fins meet the plate.
3,852 facets. Fronts face outward (counter-clockwise about the outward normal).
Deterministic; no dependencies: python3 make_heat_sink.py [out.stl]
"""
import math
import struct
import sys

FINS, TIP_SEGMENTS = 24, 38
LX, LY, BASE = 0.100, 0.080, 0.006  # plate (m)
FIN_T, FIN_H = 0.0012, 0.035  # fin thickness, height above the plate (m)

tris = []


def quad(a, b, c, d):  # counter-clockwise about the outward normal
    tris.append((a, b, c))
    tris.append((a, c, d))


def box_faces(x0, x1, y0, y1, z0, z1, skip_top=False):
    p = lambda x, y, z: (x, y, z)
    quad(p(x0, y0, z0), p(x0, y1, z0), p(x1, y1, z0), p(x1, y0, z0))  # bottom (-z)
    if not skip_top:
        quad(p(x0, y0, z1), p(x1, y0, z1), p(x1, y1, z1), p(x0, y1, z1))
    quad(p(x0, y0, z0), p(x1, y0, z0), p(x1, y0, z1), p(x0, y0, z1))  # -y
    quad(p(x0, y1, z0), p(x0, y1, z1), p(x1, y1, z1), p(x1, y1, z0))  # +y
    quad(p(x0, y0, z0), p(x0, y0, z1), p(x0, y1, z1), p(x0, y1, z0))  # -x
    quad(p(x1, y0, z0), p(x1, y1, z0), p(x1, y1, z1), p(x1, y0, z1))  # +x


box_faces(0.0, LX, 0.0, LY, 0.0, BASE, skip_top=True)
pitch = LY / FINS
gap_starts = [0.0]
for f in range(FINS):
    y0 = (f + 0.5) * pitch - FIN_T / 2
    y1 = y0 + FIN_T
    gap_starts.append(y1)
    # The fin's cross-section (y, z), counter-clockwise seen from +x: up the +y side, over
    # the round tip, down the -y side.
    r, yc, zt = FIN_T / 2, (y0 + y1) / 2, BASE + FIN_H - FIN_T / 2
    section = [(y1, BASE)]
    for k in range(TIP_SEGMENTS + 1):
        t = math.pi * k / TIP_SEGMENTS
        section.append((yc + r * math.cos(t), zt + r * math.sin(t)))
    section.append((y0, BASE))
    for k in range(len(section) - 1):  # sides and tip: strips along x
        (ya, za), (yb, zb) = section[k], section[k + 1]
        quad((0.0, ya, za), (0.0, yb, zb), (LX, yb, zb), (LX, ya, za))
    for k in range(1, len(section) - 1):  # end caps: fans from the first corner
        (ya, za), (yb, zb), (yc2, zc) = section[0], section[k], section[k + 1]
        tris.append(((LX, ya, za), (LX, yb, zb), (LX, yc2, zc)))  # +x
        tris.append(((0.0, ya, za), (0.0, yc2, zc), (0.0, yb, zb)))  # -x
gap_ends = [(f + 0.5) * pitch - FIN_T / 2 for f in range(FINS)] + [LY]
for ya, yb in zip(gap_starts, gap_ends):  # the plate's top between the fins
    quad((0.0, ya, BASE), (LX, ya, BASE), (LX, yb, BASE), (0.0, yb, BASE))


def normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    s = math.sqrt(sum(x * x for x in n))
    return tuple(x / s for x in n)


out = sys.argv[1] if len(sys.argv) > 1 else "heat_sink.stl"
with open(out, "wb") as f:
    f.write(b"lambert stand-in heat sink, metres".ljust(80, b" "))
    f.write(struct.pack("<I", len(tris)))
    for t in tris:
        f.write(struct.pack("<3f", *normal(*t)))
        for p in t:
            f.write(struct.pack("<3f", *p))
        f.write(struct.pack("<H", 0))
print(f"{out}: {len(tris)} facets")
