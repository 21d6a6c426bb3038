#!/usr/bin/env python3
"""Writes atrium.obj and atrium.mtl: a stand-in for Crytek Sponza (PROVENANCE.md).

A two-storey colonnaded courtyard in centimetres (26 m x 12 m x 8 m), open to the sky: an
undulating tiled courtyard floor (warped quads), galleries on both long sides behind
columns (12-gon prisms) carrying round arches (fans of thin triangles, T-junctions on the
columns), an upper gallery floor, back walls with window openings, end walls with plaques
lying on them (coincident faces), a roof over the galleries and draped curtains (wavy,
warped quads) hanging between the upper columns. Nothing emits: it is lit by --sky/--sun
(or --emit). Deterministic: `python3 make_atrium.py DIR` rewrites both files byte for byte.
"""
import math
import os
import sys

V = []      # vertices
G = []      # (group, material, [faces as vertex index lists])
MATS = {
    "stone": (0.62, 0.58, 0.50),
    "floor": (0.55, 0.52, 0.48),
    "plaster": (0.72, 0.68, 0.60),
    "roof": (0.45, 0.40, 0.36),
    "curtain_red": (0.60, 0.12, 0.10),
    "curtain_green": (0.12, 0.45, 0.15),
    "curtain_blue": (0.12, 0.18, 0.55),
    "bronze": (0.40, 0.30, 0.15),
}


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def newell(poly):
    n = [0.0, 0.0, 0.0]
    for i, p in enumerate(poly):
        q = poly[(i + 1) % len(poly)]
        n[0] += (p[1] - q[1]) * (p[2] + q[2])
        n[1] += (p[2] - q[2]) * (p[0] + q[0])
        n[2] += (p[0] - q[0]) * (p[1] + q[1])
    return n


class Group:
    def __init__(self, name, material):
        self.faces = []
        G.append((name, material, self.faces))

    def add(self, poly, toward):
        """Adds a polygon, wound so that its front faces along `toward`."""
        n = newell(poly)
        if n[0] * toward[0] + n[1] * toward[1] + n[2] * toward[2] < 0:
            poly = poly[::-1]
        base = len(V)
        V.extend(poly)
        self.faces.append(list(range(base + 1, base + 1 + len(poly))))


def box_faces(g, lo, hi, skip=()):
    """The six faces of an axis-aligned box, fronts outward (`skip`: sides left out)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    sides = {
        "-x": ([(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], (-1, 0, 0)),
        "+x": ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (1, 0, 0)),
        "-y": ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, -1, 0)),
        "+y": ([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, 1, 0)),
        "-z": ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, -1)),
        "+z": ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, 1)),
    }
    for key, (poly, toward) in sides.items():
        if key not in skip:
            g.add(poly, toward)


def column(g, cx, cz, y0, y1, r=25.0, sides=12):
    ring = [(cx + r * math.cos(2 * math.pi * k / sides), cz + r * math.sin(2 * math.pi * k / sides))
            for k in range(sides)]
    for k in range(sides):
        (ax, az), (bx, bz) = ring[k], ring[(k + 1) % sides]
        mid = ((ax + bx) / 2 - cx, 0.0, (az + bz) / 2 - cz)
        g.add([(ax, y0, az), (bx, y0, bz), (bx, y1, bz), (ax, y1, az)], mid)


def arch(g, x0, x1, z_face, depth_dir, y_spring, y_top, segments=12):
    """A round arch between columns at x0 and x1 (centre lines), in the plane z = z_face and
    its back at z_face + depth: the two spandrel faces as fans of thin triangles from the
    top corners, the intrados as quads. T-junctions: the springing points lie on the
    columns' faces but are no corners of them."""
    r = (x1 - x0) / 2 - 25.0
    cx = (x0 + x1) / 2
    pts = [(cx - r * math.cos(math.pi * k / segments), y_spring + r * math.sin(math.pi * k / segments))
           for k in range(segments + 1)]
    depth = 50.0
    for z, toward in ((z_face, (0, 0, -depth_dir)), (z_face + depth_dir * depth, (0, 0, depth_dir))):
        left, right = (cx - r, y_top), (cx + r, y_top)
        half = segments // 2
        for k in range(half):  # left half: fan from the top-left corner
            a, b = pts[k], pts[k + 1]
            g.add([(left[0], left[1], z), (a[0], a[1], z), (b[0], b[1], z)], toward)
        for k in range(half, segments):  # right half: fan from the top-right corner
            a, b = pts[k], pts[k + 1]
            g.add([(right[0], right[1], z), (a[0], a[1], z), (b[0], b[1], z)], toward)
        g.add([(left[0], left[1], z), (pts[half][0], pts[half][1], z), (right[0], right[1], z)],
              toward)
    for k in range(segments):  # the intrados, facing down into the opening
        a, b = pts[k], pts[k + 1]
        za, zb = z_face, z_face + depth_dir * depth
        down = (cx - (a[0] + b[0]) / 2, y_spring - (a[1] + b[1]) / 2, 0.0)
        g.add([(a[0], a[1], za), (b[0], b[1], za), (b[0], b[1], zb), (a[0], a[1], zb)], down)


def wavy(g, x0, x1, y0, y1, z0, amplitude, nu, nv, toward, phase=0.0):
    """A hanging cloth from (x0, y1) to (x1, y0) at z0 with folds along x (warped quads)."""
    def p(i, j):
        x = x0 + (x1 - x0) * i / nu
        y = y1 - (y1 - y0) * j / nv
        s = j / nv
        z = z0 + amplitude * (0.3 + 0.7 * s) * math.sin(2 * math.pi * 3 * i / nu + phase + 0.8 * s)
        return (x, y, z)
    for j in range(nv):
        for i in range(nu):
            g.add([p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)], toward)


def build():
    X, Zc, Zg, H1, H2 = 1300.0, 300.0, 600.0, 400.0, 800.0  # half length, court, gallery, floors
    court = Group("courtyard_floor", "floor")
    n_x, n_z = 52, 12  # 50 cm tiles, slightly undulating (drainage): warped quads
    def h(x, z):
        return 1.5 * math.sin(x / 140.0) * math.cos(z / 110.0)
    for i in range(n_x):
        for k in range(n_z):
            xa, xb = -X + 2 * X * i / n_x, -X + 2 * X * (i + 1) / n_x
            za, zb = -Zc + 2 * Zc * k / n_z, -Zc + 2 * Zc * (k + 1) / n_z
            court.add([(xa, h(xa, za), za), (xb, h(xb, za), za), (xb, h(xb, zb), zb),
                       (xa, h(xa, zb), zb)], (0, 1, 0))
    for side in (-1, 1):
        tag = "north" if side > 0 else "south"
        gf = Group(f"gallery_floor_{tag}", "floor")
        for i in range(26):
            xa, xb = -X + 100 * i, -X + 100 * (i + 1)
            gf.add([(xa, 0, side * Zc), (xb, 0, side * Zc), (xb, 0, side * Zg), (xa, 0, side * Zg)],
                   (0, 1, 0))
        slab = Group(f"upper_floor_{tag}", "stone")  # the upper gallery's floor, both sides
        for i in range(13):
            xa, xb = -X + 200 * i, -X + 200 * (i + 1)
            slab.add([(xa, H1, side * Zc), (xb, H1, side * Zc), (xb, H1, side * Zg),
                      (xa, H1, side * Zg)], (0, 1, 0))
            slab.add([(xa, H1 - 30, side * Zc), (xb, H1 - 30, side * Zc), (xb, H1 - 30, side * Zg),
                      (xa, H1 - 30, side * Zg)], (0, -1, 0))
        roof = Group(f"roof_{tag}", "roof")
        roof.add([(-X, H2, side * Zc), (X, H2, side * Zc), (X, H2, side * Zg), (-X, H2, side * Zg)],
                 (0, -1, 0))
        wall = Group(f"back_wall_{tag}", "plaster")
        # Lower storey solid; upper storey with 12 window openings 100 wide, 150 tall.
        wall.add([(-X, 0, side * Zg), (X, 0, side * Zg), (X, H1, side * Zg), (-X, H1, side * Zg)],
                 (0, 0, -side))
        xs = [-X + 50]
        for i in range(12):
            c = -X + 100 + (2 * X - 200) * (i + 0.5) / 12
            xs += [c - 50, c + 50]
        xs.append(X - 50)
        wall.add([(-X, H1, side * Zg), (-X + 50, H1, side * Zg), (-X + 50, H2, side * Zg),
                  (-X, H2, side * Zg)], (0, 0, -side))
        wall.add([(X - 50, H1, side * Zg), (X, H1, side * Zg), (X, H2, side * Zg),
                  (X - 50, H2, side * Zg)], (0, 0, -side))
        for i in range(0, len(xs) - 1):
            xa, xb = xs[i], xs[i + 1]
            if i % 2 == 1:  # an opening: a sill below and a lintel above it
                wall.add([(xa, H1, side * Zg), (xb, H1, side * Zg), (xb, H1 + 120, side * Zg),
                          (xa, H1 + 120, side * Zg)], (0, 0, -side))
                wall.add([(xa, H1 + 270, side * Zg), (xb, H1 + 270, side * Zg), (xb, H2, side * Zg),
                          (xa, H2, side * Zg)], (0, 0, -side))
            else:
                wall.add([(xa, H1, side * Zg), (xb, H1, side * Zg), (xb, H2, side * Zg),
                          (xa, H2, side * Zg)], (0, 0, -side))
        cols = Group(f"columns_{tag}", "stone")
        arches = Group(f"arches_{tag}", "stone")
        xs_col = [-X + 100 + 200 * i for i in range(13)]
        for cx in xs_col:
            column(cols, cx, side * Zc, 0.0, 300.0)
            column(cols, cx, side * Zc, H1, H1 + 250.0)
        for a, b in zip(xs_col, xs_col[1:]):
            arch(arches, a, b, side * (Zc - 25), side, 290.0, H1 - 30)
        # Piers from the capitals to the slab, the slab's front edge and the upper beam
        # carrying the roof: the facade's solid parts (T-junctions where they meet).
        for cx in xs_col:
            box_faces(arches, (cx - 25, 300.0, side * Zc - 25), (cx + 25, H1 - 30, side * Zc + 25),
                      skip=("-y", "+y"))
        front = Group(f"facade_{tag}", "stone")
        zf = side * (Zc - 25)
        front.add([(-X, H1 - 30, zf), (X, H1 - 30, zf), (X, H1, zf), (-X, H1, zf)], (0, 0, -side))
        box_faces(front, (-X, H1 + 250, min(zf, side * (Zc + 25))),
                  (X, H2, max(zf, side * (Zc + 25))), skip=("-x", "+x"))
        if side > 0:
            for i, colour in enumerate(("curtain_red", "curtain_green", "curtain_blue",
                                        "curtain_red")):
                cloth = Group(f"curtain_{i}", colour)
                a, b = xs_col[2 + 3 * i], xs_col[3 + 3 * i]
                wavy(cloth, a + 30, b - 30, H1 + 20, H1 + 240, side * (Zc - 10), 12.0, 16, 12,
                     (0, 0, -side), phase=i)
    ends = Group("end_walls", "plaster")
    for sx in (-1, 1):
        ends.add([(sx * X, 0, -Zg), (sx * X, 0, Zg), (sx * X, H2, Zg), (sx * X, H2, -Zg)],
                 (-sx, 0, 0))
    plaques = Group("plaques", "bronze")  # lying exactly on the end walls: coincident faces
    for sx in (-1, 1):
        plaques.add([(sx * X, 150, -60), (sx * X, 150, 60), (sx * X, 230, 60), (sx * X, 230, -60)],
                    (-sx, 0, 0))
    fountain = Group("fountain", "stone")  # a basin standing on the courtyard floor
    box_faces(fountain, (-120, -1.5, -80), (120, 60, 80), skip=("-y",))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    build()
    with open(os.path.join(out, "atrium.mtl"), "w") as f:
        for name, (r, g, b) in MATS.items():
            f.write(f"newmtl {name}\nKd {r:.2f} {g:.2f} {b:.2f}\n")
    with open(os.path.join(out, "atrium.obj"), "w") as f:
        f.write("# lambert data/atrium: a Sponza stand-in (PROVENANCE.md), centimetres, y up\n")
        f.write("mtllib atrium.mtl\n")
        for x, y, z in V:
            f.write(f"v {x:.4f} {y:.4f} {z:.4f}\n")
        for name, material, faces in G:
            f.write(f"g {name}\nusemtl {material}\n")
            for face in faces:
                f.write("f " + " ".join(str(i) for i in face) + "\n")


if __name__ == "__main__":
    main()
