#!/usr/bin/env python3
"""Writes data/cornell_box_specular/ from the measured Cornell box in data/cornell_box/.

The room, the light and the tall block are copied unchanged (coordinate strings included);
the tall block gets the mirror material; the short block is removed and a glass icosphere
rests on the floor where it stood. Standard library only; output is deterministic.

Usage: scripts/make_cornell_specular.py [--source data/cornell_box] [--out data/cornell_box_specular]
"""

import argparse
import math
import os
import shutil
import sys

NAME = "cornell_box_specular"
RADIUS = 85.0          # mm; the short block's footprint is ~165 mm wide
LIFT = 0.5             # mm between the floor and the sphere's lowest vertex
SUBDIVISIONS = 3       # icosahedron split 3 times: 20 * 4^3 = 1280 triangles
DROP = {"short_block"}
MATERIAL_OF = {"tall_block": "mirror"}

MIRROR_GLASS_MTL = """
# Added by scripts/make_cornell_specular.py (not measured):
# a mirror that keeps 5 % absorption (illum 3: reflection, Kd + Ks <= 1 per channel).
newmtl mirror
Kd 0 0 0
Ks 0.95 0.95 0.95
illum 3

# Clear glass (illum 7: Fresnel reflection and refraction; dielectrics need Kd 0).
newmtl glass
Kd 0 0 0
Ni 1.5
Tf 1 1 1
illum 7
"""


def read_obj(path):
    """Returns (vertex strings, [(group, material, [faces as 0-based index lists])])."""
    verts, groups = [], []
    group, material = "default", None
    with open(path, encoding="utf-8") as f:
        for line in f:
            tok = line.split()
            if not tok or tok[0].startswith("#"):
                continue
            if tok[0] == "v":
                verts.append(tok[1:4])
            elif tok[0] == "g":
                group = " ".join(tok[1:])
            elif tok[0] == "usemtl":
                material = " ".join(tok[1:])
            elif tok[0] == "f":
                face = [int(t.split("/")[0]) - 1 for t in tok[1:]]
                if not groups or groups[-1][0] != group or groups[-1][1] != material:
                    groups.append((group, material, []))
                groups[-1][2].append(face)
            elif tok[0] != "mtllib":
                sys.exit(f"{path}: unexpected statement '{tok[0]}'")
    return verts, groups


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def unit(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def icosphere(levels):
    """Unit icosphere with a vertex at each pole (+y, -y); triangles counter-clockwise seen
    from outside."""
    pts = [(0.0, 1.0, 0.0)]
    y, r = 1.0 / math.sqrt(5.0), 2.0 / math.sqrt(5.0)
    for k in range(5):
        a = 2.0 * math.pi * k / 5.0
        pts.append((r * math.cos(a), y, r * math.sin(a)))
    for k in range(5):
        a = 2.0 * math.pi * (k + 0.5) / 5.0
        pts.append((r * math.cos(a), -y, r * math.sin(a)))
    pts.append((0.0, -1.0, 0.0))
    tris = []
    for k in range(5):
        u0, u1 = 1 + k, 1 + (k + 1) % 5
        l0, l1 = 6 + k, 6 + (k + 1) % 5
        tris += [(0, u0, u1), (u0, l0, u1), (u1, l0, l1), (11, l1, l0)]
    for _ in range(levels):
        mid = {}

        def middle(i, j):
            key = (min(i, j), max(i, j))
            if key not in mid:
                a, b = pts[i], pts[j]
                pts.append(unit(((a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2)))
                mid[key] = len(pts) - 1
            return mid[key]

        out = []
        for a, b, c in tris:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
        tris = out
    # Orient every triangle outward (the right-hand normal away from the centre).
    tris = [t if dot(cross(sub(pts[t[1]], pts[t[0]]), sub(pts[t[2]], pts[t[0]])), pts[t[0]]) > 0
            else (t[0], t[2], t[1]) for t in tris]
    return pts, tris


def distance_to_segment_2d(p, a, b):
    ab = (b[0] - a[0], b[1] - a[1])
    t = ((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / (ab[0] ** 2 + ab[1] ** 2)
    t = max(0.0, min(1.0, t))
    q = (a[0] + t * ab[0], a[1] + t * ab[1])
    return math.hypot(p[0] - q[0], p[1] - q[1])


def footprint(verts, faces):
    """x-z corners of a block's top face (the face whose corners share the largest y)."""
    top = max(faces, key=lambda f: min(float(verts[v][1]) for v in f))
    return [(float(verts[v][0]), float(verts[v][2])) for v in top]


def fmt(x):
    s = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--source", default=os.path.join(root, "data", "cornell_box"))
    ap.add_argument("--out", default=os.path.join(root, "data", NAME))
    args = ap.parse_args()
    verts, groups = read_obj(os.path.join(args.source, "cornell_box.obj"))
    blocks = {g: faces for g, _, faces in groups if g.endswith("_block")}

    # The sphere: centred over the short block's footprint, lowest vertex LIFT above y = 0.
    short = footprint(verts, blocks["short_block"])
    cx = sum(p[0] for p in short) / len(short)
    cz = sum(p[1] for p in short) / len(short)
    cy = RADIUS + LIFT
    tall = footprint(verts, blocks["tall_block"])
    gap_tall = min(distance_to_segment_2d((cx, cz), tall[k], tall[(k + 1) % len(tall)])
                   for k in range(len(tall))) - RADIUS
    gap_wall = min(cx, cz, 549.6 - cx, 559.2 - cz) - RADIUS  # green wall x = 0, front z = 0
    if gap_tall <= 1.0 or gap_wall <= 1.0:
        sys.exit(f"sphere too close: {gap_tall:.1f} mm to the tall block, {gap_wall:.1f} to a wall")
    unit_pts, tris = icosphere(SUBDIVISIONS)
    sphere = [(cx + RADIUS * p[0], cy + RADIUS * p[1], cz + RADIUS * p[2]) for p in unit_pts]
    assert min(p[1] for p in sphere) == LIFT

    os.makedirs(args.out, exist_ok=True)
    lines = [
        "# Cornell box with specular parts, written by scripts/make_cornell_specular.py from",
        "# data/cornell_box/cornell_box.obj (see PROVENANCE.md): the measured room, light and tall",
        "# block unchanged (the tall block is now a mirror), the short block replaced by a glass",
        f"# icosphere of radius {fmt(RADIUS)} mm ({len(tris)} triangles, wound outward) centred at",
        f"# ({fmt(cx)}, {fmt(cy)}, {fmt(cz)}), its lowest vertex {fmt(LIFT)} mm above the floor.",
        f"# Clearances: {gap_tall:.1f} mm to the tall block, {gap_wall:.1f} mm to the walls/front.",
        f"mtllib {NAME}.mtl",
    ]
    count = 0
    for group, material, faces in groups:
        if group in DROP:
            continue
        lines += ["", f"g {group}", f"usemtl {MATERIAL_OF.get(group, material)}"]
        for face in faces:
            lines += ["v " + " ".join(verts[v]) for v in face]
            lines.append("f " + " ".join(str(count + 1 + k) for k in range(len(face))))
            count += len(face)
    lines += ["", "g glass_sphere", "usemtl glass"]
    lines += [f"v {fmt(p[0])} {fmt(p[1])} {fmt(p[2])}" for p in sphere]
    lines += [f"f {count + 1 + a} {count + 1 + b} {count + 1 + c}" for a, b, c in tris]
    with open(os.path.join(args.out, NAME + ".obj"), "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(lines) + "\n")

    with open(os.path.join(args.source, "cornell_box.mtl"), encoding="utf-8") as f:
        mtl = f.read()
    with open(os.path.join(args.out, NAME + ".mtl"), "w", encoding="utf-8", newline="\n") as f:
        f.write("# Materials of cornell_box.mtl (measured; unchanged), then the mirror and glass.\n")
        f.write(mtl.rstrip("\n") + "\n" + MIRROR_GLASS_MTL)
    shutil.copyfile(os.path.join(args.source, "cornell_box.camera"),
                    os.path.join(args.out, NAME + ".camera"))
    print(f"{args.out}: {len(tris)} sphere triangles, centre ({fmt(cx)}, {fmt(cy)}, {fmt(cz)}), "
          f"clearance {gap_tall:.1f} mm (tall block), {gap_wall:.1f} mm (walls)", file=sys.stderr)


if __name__ == "__main__":
    main()
