#!/usr/bin/env python3
"""Writes the Stanford bunny standing in the Cornell box (issue 35's first scene) as one OBJ:
the box from data/cornell_box without its tall block, and bun_zipper_res4.ply (946
triangles; its holes left open) scaled to 180 units tall and turned to face the camera, standing on the floor where the
tall block stood. Usage: python3 make_bunny_in_box.py OUT.obj (OUT.mtl beside it).
Then: lambert run OUT.obj (docs/scenes.md shows the picture)."""
import os
import sys

here = os.path.dirname(os.path.abspath(__file__))
box = os.path.join(here, "..", "cornell_box", "cornell_box.obj")
ply = os.path.join(here, "bun_zipper_res4.ply")
out = sys.argv[1]

with open(ply) as f:
    lines = f.read().split("\n")
end = lines.index("end_header")
nv = int(next(l for l in lines if l.startswith("element vertex")).split()[2])
nf = int(next(l for l in lines if l.startswith("element face")).split()[2])
verts = [tuple(map(float, l.split()[:3])) for l in lines[end + 1:end + 1 + nv]]
faces = [list(map(int, l.split()[1:])) for l in lines[end + 1 + nv:end + 1 + nv + nf]]
lo = [min(v[k] for v in verts) for k in range(3)]
hi = [max(v[k] for v in verts) for k in range(3)]
s = 180.0 / (hi[1] - lo[1])
cx, cz = 348.0, 378.0  # where the tall block stood (its footprint's centre)
# Turned half round about the vertical (a rotation: fronts stay fronts) to face the camera.
bunny = [(-(x - (lo[0] + hi[0]) / 2) * s + cx, (y - lo[1]) * s + 0.5,
          -(z - (lo[2] + hi[2]) / 2) * s + cz) for x, y, z in verts]

obj, n_box, skip = [], 0, False
with open(box) as f:
    for line in f:
        if line.startswith("mtllib"):
            line = "mtllib " + os.path.splitext(os.path.basename(out))[0] + ".mtl\n"
        if line.startswith("g "):
            skip = line.strip() == "g tall_block"
        if skip and not line.startswith("v "):
            continue  # the tall block's faces go (its vertices stay: indices keep counting)
        obj.append(line)
        n_box += line.startswith("v ")
obj.append("g bunny\nusemtl white\n")
obj += [f"v {x:.4f} {y:.4f} {z:.4f}\n" for x, y, z in bunny]
obj += ["f " + " ".join(str(n_box + 1 + i) for i in face) + "\n" for face in faces]
with open(out, "w") as f:
    f.writelines(obj)
with open(os.path.join(here, "..", "cornell_box", "cornell_box.mtl")) as src, \
        open(os.path.splitext(out)[0] + ".mtl", "w") as dst:
    dst.write(src.read())
