#!/usr/bin/env python3
"""Draws a VTU of `lambert heat -o X.vtu` (or any VTU of triangles and quads with a cell
array) as a PNG: cutaway views, each cell flat-coloured by the array with viridis and a
colour bar. The cells whose front (the side that emits) faces away from the viewer are left
out, so that an enclosure's near walls are open and its inside is seen (by default from
above and from below: the floor, then the ceiling). Reads the file with
meshio (Debian: python3-meshio); made docs/thermal_vtu.png:

  lambert heat data/thermal_box/thermal_box.stl --surfaces data/thermal_box/surfaces.json \\
      --length-unit mm -o box.vtu
  scripts/plot_vtu.py box.vtu docs/thermal_vtu.png --array T_K
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402


def view_direction(elev, azim):
    """Unit vector from the scene towards matplotlib's camera at (elev, azim) degrees."""
    e, a = np.radians(elev), np.radians(azim)
    return np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])


def cutaway(ax, m, values, elev, azim, norm):
    """Draws the cells of `m` whose front faces the camera at (elev, azim), coloured by
    `values` (one per cell, in cell order) with viridis over `norm`; NaN grey."""
    towards_viewer = view_direction(elev, azim)
    polygons, shown = [], []
    k = 0
    for block in m.cells:
        for cell in block.data:
            p = m.points[cell]
            normal = np.cross(p[1] - p[0], p[2] - p[0])  # front: counter-clockwise corners
            if normal @ towards_viewer > 0:
                polygons.append(p)
                shown.append(values[k])
            k += 1
    shown = np.array(shown)
    colours = plt.cm.viridis(norm(shown))
    colours[~np.isfinite(shown)] = (0.8, 0.8, 0.8, 1.0)  # undefined: grey
    ax.add_collection3d(Poly3DCollection(polygons, facecolors=colours, edgecolors=(0, 0, 0, 0.15),
                                         linewidths=0.3))
    lo, hi = m.points.min(axis=0), m.points.max(axis=0)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(hi - lo)
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()
    ax.set_title(f"seen from {'above' if elev >= 0 else 'below'} (elev {elev:g}\N{DEGREE SIGN})",
                 fontsize=9)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("vtu")
    ap.add_argument("png")
    ap.add_argument("--array", default="T_K", help="cell array to colour by (default T_K)")
    ap.add_argument("--view", action="append", metavar="ELEV,AZIM",
                    help="a view in degrees, one panel each (default: 35,-60 and -35,-60)")
    ap.add_argument("--title", default=None)
    args = ap.parse_args()

    m = meshio.read(args.vtu)
    values = np.concatenate(m.cell_data[args.array])
    finite = values[np.isfinite(values)]
    lo, hi = finite.min(), finite.max()
    norm = plt.Normalize(lo, hi if hi > lo else lo + 1.0)
    views = [tuple(map(float, v.split(","))) for v in (args.view or ["35,-60", "-35,-60"])]
    fig = plt.figure(figsize=(3.4 * len(views) + 1.0, 3.6), dpi=100)
    axes = [fig.add_subplot(1, len(views), k + 1, projection="3d") for k in range(len(views))]
    for ax, (elev, azim) in zip(axes, views):
        cutaway(ax, m, values, elev, azim, norm)
    bar = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap="viridis"), ax=axes, shrink=0.7,
                       pad=0.02)
    bar.set_label(args.array)
    fig.suptitle(args.title or f"{args.vtu.split('/')[-1]}: cell data {args.array}", fontsize=10)
    fig.savefig(args.png, bbox_inches="tight")


if __name__ == "__main__":
    main()
