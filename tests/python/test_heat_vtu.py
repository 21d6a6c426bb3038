"""`lambert heat -o X.vtu` read by an independent reader (meshio): the cells are the patches,
the cell data are the per-patch CSV's values, the field data the per-surface CSV's, and the
powers close."""
import csv
import json
import os

import numpy as np
import pytest

from conftest import run_cli

try:
    import meshio
except ImportError:
    pytest.skip("meshio is not installed (Debian: apt-get install python3-meshio); "
                "the VTU test reads the file with it", allow_module_level=True)

ROOT = os.path.join(os.path.dirname(__file__), "..", "..", "data", "thermal_box")
STL = os.path.join(ROOT, "thermal_box.stl")
# The worked example's command line (docs/thermal.md), small and with a fixed seed: two runs
# with the same arguments compute the same F and the same solution bit for bit.
HEAT = ["heat", STL, "--surfaces", os.path.join(ROOT, "surfaces.json"), "--length-unit", "mm",
        "--patches", 200, "--estimator", "hybrid", "--samples", 8, "--seed", 5, "--tol", 1e-10,
        "-q"]


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def number(text):
    """A CSV number; an empty field (an undefined value) is NaN."""
    return float(text) if text not in ("", "null") else float("nan")


def cell_array(mesh, name):
    """A cell array in cell order (meshio splits the cells into runs of one type, in order)."""
    return np.concatenate(mesh.cell_data[name])


def cell_areas(mesh, metres):
    """The area of every cell from the points (a quad as two triangles), in m²."""
    out = []
    for block in mesh.cells:
        p = mesh.points[block.data] * metres
        tri = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        if block.type == "quad":
            tri = tri + 0.5 * np.linalg.norm(np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]),
                                             axis=1)
        else:
            assert block.type == "triangle"
        out.append(tri)
    return np.concatenate(out)


def test_heat_vtu_holds_the_csvs_values_and_closes(tmp_path):
    run_cli(*HEAT, "-o", tmp_path / "h.vtu", "--patches-csv", tmp_path / "p.csv")
    run_cli(*HEAT, "-o", tmp_path / "s.csv")
    # -o X.vtu writes X.vtu and the summary X.json beside it, no per-surface CSV.
    assert sorted(os.listdir(tmp_path)) == ["h.json", "h.vtu", "p.csv", "s.csv", "s.json"]
    m = meshio.read(tmp_path / "h.vtu")
    patches = read_csv(tmp_path / "p.csv")
    n = len(patches)
    assert sum(len(b.data) for b in m.cells) == n

    # Cell data: the per-patch CSV's values (17 significant digits there: the doubles exactly).
    columns = {"T_K": "T_K", "q_W_m2": "q_W_m2", "Q_W": "Q_W", "J_W_m2": "J_W_m2",
               "H_W_m2": "H_W_m2", "emissivity": "emissivity", "area_m2": "area_m2"}
    for array, column in columns.items():
        expected = np.array([number(r[column]) for r in patches])
        assert np.array_equal(cell_array(m, array), expected, equal_nan=True), array

    # Field data: the per-surface table, names first (NUL-terminated UTF-8 bytes).
    names = bytes(m.field_data["surface_names"]).split(b"\0")
    assert names[-1] == b""
    names = [s.decode() for s in names[:-1]]
    surfaces = read_csv(tmp_path / "s.csv")
    assert [r["surface"] for r in surfaces] == names + ["environment"]
    rows = surfaces[:-1]
    for column in ("emissivity", "given", "area_m2", "patches", "T_mean_K", "T_min_K", "T_max_K",
                   "J_W_m2", "q_W_m2", "Q_W"):
        expected = np.array([number(r[column]) for r in rows])
        assert np.array_equal(m.field_data["surface_" + column], expected, equal_nan=True), column
    known = [1 if r["condition"] == "temperature" else 0 for r in rows]
    assert list(m.field_data["surface_known_temperature"]) == known
    env = float(surfaces[-1]["Q_W"])
    assert m.field_data["environment_W"][0] == env

    # The cells' surface index names the patch CSV's surface.
    surface = cell_array(m, "surface")
    assert [names[s] for s in surface] == [r["surface"] for r in patches]
    # The heater is at its 800 K, the cold plate at its 300 K, the walls in between.
    T = cell_array(m, "T_K")
    by = {name: T[surface == k] for k, name in enumerate(names)}
    assert np.all(by["heater"] == 800) and np.all(by["cold_plate"] == 300)
    assert np.all((by["walls"] > 300) & (by["walls"] < 800))

    # The geometry: each cell's area from its points (mm -> m) is the patch's area. The mesher's
    # areas are exact for planar patches, so they agree to rounding: a few ulps of the largest
    # coordinate squared (~1 m² · 1e-16) relative to the smallest cell (~1e-3 m²): 1e-12 rel.
    area = cell_array(m, "area_m2")
    assert np.allclose(cell_areas(m, 1e-3), area, rtol=1e-12, atol=0)

    # Energy: sum of Q over the cells + environment = closure ≈ 0. Hybrid is a pair estimator
    # (A_i F_ij = A_j F_ji to rounding), so the closure is rounding: n terms of up to max |Q|
    # summed in doubles, n * 1.1e-16 * max|Q| -- the tolerance below is 4x that.
    Q = cell_array(m, "Q_W")
    bound = 4 * n * np.finfo(float).eps * np.abs(Q).max()
    assert abs(Q.sum() + env) <= bound
    assert abs(m.field_data["closure_W"][0]) <= bound
    summary = json.loads((tmp_path / "h.json").read_text())
    assert summary["closure"]["sum_W"] == m.field_data["closure_W"][0]
    assert summary["status"] == "converged"
