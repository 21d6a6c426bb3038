"""The Python API against the CLI and against closed forms."""
import math
import os

import numpy as np
import pytest
import scipy.sparse as sp

import lambert
from conftest import run_cli, write_obj


def test_version_is_the_cli_version():
    # One version number: `lambert --version` prints "lambert X.Y.Z".
    out = run_cli("--version").stdout.strip()
    assert out == "lambert " + lambert.__version__
    assert all(part.isdigit() for part in lambert.__version__.split("."))


def test_scene_and_mesh_arrays(cornell, cornell_mesh):
    assert "floor" in " ".join(cornell.surfaces).lower() or len(cornell.surfaces) >= 5
    assert len(cornell.areas) == len(cornell.surfaces)
    m = cornell_mesh
    n = len(m)
    assert m.areas.shape == (n,) and m.normals.shape == (n, 3) and m.rho.shape == (n, 3)
    assert m.emission.shape == (n, 3) and m.centroids.shape == (n, 3)
    assert m.patch_corners.shape == (n, 4) and m.surface_ids.shape == (n,)
    # The patches tile the surfaces exactly (mesh.cpp: area exact).
    assert math.isclose(m.areas.sum(), sum(cornell.areas), rel_tol=1e-12)
    assert np.allclose(np.linalg.norm(m.normals, axis=1), 1.0)
    assert (m.emission.max(axis=1) > 0).any()
    assert m.patch_corners.max() < len(m.vertices)


def test_mesh_arrays_are_read_only_views(cornell_mesh):
    areas = cornell_mesh.areas
    assert not areas.flags.writeable and not areas.flags.owndata
    with pytest.raises(ValueError):
        areas[0] = 1.0
    # Two reads of the same member share the mesh's memory: no copy was made.
    assert np.shares_memory(cornell_mesh.rho, cornell_mesh.rho)


@pytest.mark.parametrize("estimator,count", [("hybrid", ["--samples", "8"]),
                                             ("gather", ["--rays", "256"])])
def test_form_factors_equal_the_cli_bitwise(tmp_path, cornell, estimator, count):
    mesh = cornell.mesh(patches=300)
    kwargs = {"samples": 8} if estimator == "hybrid" else {"rays": 256}
    ff = lambert.form_factors(mesh, estimator=estimator, seed=7, threads=2, **kwargs)
    F = ff.matrix
    assert isinstance(F, sp.csr_matrix) and F.shape == (len(mesh), len(mesh))
    assert not F.data.flags.owndata  # handed over from C++ without a copy
    # What made it travels with it: the settings, the computation's stats, the mesh.
    assert f"estimator={estimator}" in ff.settings and "seed=7" in ff.settings
    assert ff.stats["rays"] > 0 and ff.mesh_hash == mesh.hash and ff.stderr is None
    cli = tmp_path / "F.bin"
    run_cli("formfactors", "--patches", 300, "--estimator", estimator, *count, "--seed", 7,
            "-j", 1, "-q", "-o", cli)
    loaded = lambert.load_form_factors(cli, mesh)
    G = loaded.matrix
    assert loaded.settings == ff.settings and loaded.stats is None
    # Bitwise: the same sparsity and the same doubles (not merely close).
    assert np.array_equal(F.indptr, G.indptr) and np.array_equal(F.indices, G.indices)
    assert F.data.tobytes() == G.data.tobytes()
    # Saved from Python, the file is the CLI's byte for byte (same settings text).
    mine = tmp_path / "mine.bin"
    lambert.save_form_factors(mine, mesh, ff)
    assert mine.read_bytes() == cli.read_bytes()
    # A derived matrix is a plain scipy matrix: saved, it claims no settings. (Half of F: F's
    # own rows may exceed 1 by their Monte Carlo error, which a file without errors refuses.)
    lambert.save_form_factors(tmp_path / "derived.bin", mesh, ff.matrix * 0.5)
    assert lambert.load_form_factors(tmp_path / "derived.bin", mesh).settings == ""
    # A FormFactors of another mesh is refused before any work.
    with pytest.raises(lambert.UsageError, match="another mesh"):
        lambert.solve(cornell.mesh(patches=50), ff)


def test_save_load_round_trip_with_stderr(tmp_path, cornell_mesh):
    ff = lambert.form_factors(cornell_mesh, estimator="mc", samples=4, stderr=True)
    F, S = ff.matrix, ff.stderr
    assert S is not None and S.shape == F.shape
    lambert.save_form_factors(tmp_path / "F.bin", cornell_mesh, ff)  # F, S and the settings
    loaded = lambert.load_form_factors(tmp_path / "F.bin", cornell_mesh)
    assert (loaded.matrix != F).nnz == 0 and (loaded.stderr != S).nnz == 0
    assert loaded.settings == ff.settings
    lambert.save_form_factors(tmp_path / "F.mtx", cornell_mesh, ff)  # F and its settings
    assert (lambert.load_form_factors(tmp_path / "F.mtx", cornell_mesh).matrix != F).nnz == 0


def cube_faces():
    """The unit cube's six faces wound about their inward normals."""
    faces = {}
    for a in range(3):
        u, v = (a + 1) % 3, (a + 2) % 3
        for s in (0, 1):
            p = []
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                c = [0.0, 0.0, 0.0]
                c[a], c[u], c[v] = float(s), float(du), float(dv)
                p.append(tuple(c))
            faces[f"f{a}{s}"] = [p if s == 0 else p[::-1]]
    return faces


def test_furnace_gives_e_over_one_minus_rho(tmp_path):
    rho, e = 0.5, 1.0
    faces = cube_faces()
    path = write_obj(tmp_path / "cube.obj", faces, {k: ((rho,) * 3, (e,) * 3) for k in faces})
    mesh = lambert.load_scene(path).mesh(max_edge=0.5)
    n = len(mesh)
    tol_f, tol = 1e-9, 1e-10
    F = lambert.form_factors(mesh, estimator="analytic", tol=tol_f)
    B, report = lambert.solve(mesh, F, solver="gauss-seidel", tol=tol)
    assert report["status"] == "converged"
    # Bound: ||K^-1||_inf <= 1/(1 - rho) = 2 turns the stopping rule ||E - K B|| <= tol ||E||
    # into |B - B*| <= 2 tol ||E||_2 = 2 tol sqrt(n); each row of F is off by at most n tol_f,
    # which moves B* by at most 2 rho (n tol_f) max B = 2 n tol_f.
    bound = 2 * tol * math.sqrt(n) * e + 2 * n * tol_f
    assert np.abs(B - e / (1 - rho)).max() <= bound
    for ch in report["energy"]:
        assert ch["escaped"] <= 2 * n * tol_f * ch["emitted"]


def parallel_squares_factor(x, y):
    """F between parallel, directly opposed rectangles of sides x, y at unit distance."""
    a, b = 1 + x * x, 1 + y * y
    return 2 / (math.pi * x * y) * (
        math.log(math.sqrt(a * b / (a + b - 1))) + x * math.sqrt(b) * math.atan(x / math.sqrt(b))
        + y * math.sqrt(a) * math.atan(y / math.sqrt(a)) - x * math.atan(x) - y * math.atan(y))


def test_parallel_squares_within_four_standard_errors(tmp_path):
    bottom = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    top = [(0, 0, 1), (0, 1, 1), (1, 1, 1), (1, 0, 1)]
    path = write_obj(tmp_path / "squares.obj", {"bottom": [bottom], "top": [top]})
    mesh = lambert.load_scene(path).mesh(max_edge=0.25)
    ff = lambert.form_factors(mesh, estimator="mc", samples=64, seed=3, stderr=True)
    F, S = ff.matrix, ff.stderr
    ids, A = mesh.surface_ids, mesh.areas
    b, t = ids == mesh.surface_names.index("bottom"), ids == mesh.surface_names.index("top")
    Ab = A[b].sum()
    F_bt = (A[b][:, None] * F[b][:, t].toarray()).sum() / Ab
    # The entries' estimates are independent (one stream per pair), so the surface factor's
    # standard error is the root sum of squares of the area-weighted entry errors.
    se = math.sqrt(((A[b][:, None] * S[b][:, t].toarray()) ** 2).sum()) / Ab
    exact = parallel_squares_factor(1.0, 1.0)  # 0.19982
    assert se > 0
    assert abs(F_bt - exact) <= 4 * se, (F_bt, exact, se)


def test_two_solvers_agree_and_report(cornell_mesh):
    F = lambert.form_factors(cornell_mesh, estimator="hybrid", samples=8)
    B1, r1 = lambert.solve(cornell_mesh, F, solver="gauss-seidel", tol=1e-10)
    solution = lambert.solve(cornell_mesh, F.matrix, solver="cg", tol=1e-10)  # a plain matrix too
    B2, r2 = solution
    assert solution.B is B2 and solution.report is r2
    assert B1.shape == (len(cornell_mesh), 3) and r1["status"] == r2["status"] == "converged"
    assert len(r1["channels"]) == 3 and r1["channels"][0]["residual_history"]
    assert r1["residual"] <= 1e-10
    # Both meet ||E - K B|| <= 1e-10 ||E||; K^-1 <= 1/(1 - rho_max) (rho_max = 0.78 the light).
    assert np.abs(B1 - B2).max() <= 2 * 1e-10 * np.linalg.norm(cornell_mesh.emission) / (1 - 0.78)
    assert (B1 >= cornell_mesh.emission - 1e-12).all()


def test_vertex_field_render_and_files(tmp_path, cornell_mesh):
    F = lambert.form_factors(cornell_mesh, estimator="hybrid", samples=4)
    B, _ = lambert.solve(cornell_mesh, F)
    field = lambert.vertex_radiosity(cornell_mesh, B)
    assert field.values.shape == (len(field), 3) and field.positions.shape == (len(field), 3)
    lambert.write_vertex_exr(tmp_path / "v.exr", cornell_mesh, B)
    assert (tmp_path / "v.exr").stat().st_size > 0
    img = lambert.render(cornell_mesh, B, width=32, height=24, antialias=1,
                         exr=tmp_path / "r.exr", png=tmp_path / "r.png")
    assert img.shape == (24, 32, 3) and img.dtype == np.float32 and img.max() > 0
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"


def test_render_with_F_draws_the_direct_light_per_pixel(tmp_path):
    # The partial-shadow scene (geometry/analytic.hpp): only the floor reflects, so its
    # indirect light is exactly 0 and, with F, every umbra pixel is exactly 0 (the shadow
    # per pixel); from the vertices (no F) the umbra is smeared over the 0.5 patches.
    floor = [(0, 0, 0), (4, 0, 0), (4, 4, 0), (0, 4, 0)]
    light = [(1.5, 1.5, 3), (1.5, 2.5, 3), (2.5, 2.5, 3), (2.5, 1.5, 3)]
    blocker = [(1.6, 1.3, 1.5), (2.6, 1.3, 1.5), (2.6, 2.1, 1.5), (1.6, 2.1, 1.5)]
    path = write_obj(tmp_path / "ps.obj", {"floor": [floor], "light": [light], "blocker": [blocker]},
                     {"floor": ((0.5,) * 3, (0,) * 3), "light": ((0,) * 3, (1,) * 3),
                      "blocker": ((0,) * 3, (0,) * 3)})
    mesh = lambert.load_scene(path).mesh(max_edge=0.5)
    F = lambert.form_factors(mesh, estimator="hybrid", samples=4)
    B, _ = lambert.solve(mesh, F)
    view = dict(eye=(2, -2, 2.4), look_at=(2, 2, 0), up=(0, 0, 1), fov=60, width=48, height=48,
                antialias=1)
    per_pixel = lambert.render(mesh, B, F=F, threads=1, **view)
    assert np.array_equal(per_pixel, lambert.render(mesh, B, F=F, threads=2, **view))
    from_vertices = lambert.render(mesh, B, **view)
    zeros = lambda img: int((img[..., 1] == 0).sum())  # noqa: E731 (misses, black faces, umbra)
    assert zeros(per_pixel) > zeros(from_vertices) + 20
    assert per_pixel.max() > 0
    # What cannot draw it refuses F or direct_rays, never ignores them.
    with pytest.raises(lambert.UsageError, match="gouraud"):
        lambert.render(mesh, B, F=F, shading="flat", **view)
    with pytest.raises(lambert.UsageError, match="needs F"):
        lambert.render(mesh, B, direct_rays=4, **view)
    with pytest.raises(lambert.UsageError, match="leave F out"):
        lambert.render(mesh, B, F=F, direct_rays=0, **view)
    with pytest.raises(lambert.UsageError, match="direct_rays"):
        lambert.render(mesh, B, F=F, direct_rays=-1, **view)


def test_bad_files_raise_input_error_naming_the_file(tmp_path, cornell_mesh):
    missing = tmp_path / "missing.obj"
    with pytest.raises(lambert.InputError, match="missing.obj"):
        lambert.load_scene(missing)
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(lambert.InputError, match="bad.obj"):
        lambert.load_scene(bad)
    # An F made for another mesh is refused, naming the file.
    other = lambert.load_scene().mesh(patches=50)
    lambert.save_form_factors(tmp_path / "other.bin", other,
                              lambert.form_factors(other, estimator="hybrid", samples=2))
    with pytest.raises(lambert.InputError, match="other.bin"):
        lambert.load_form_factors(tmp_path / "other.bin", cornell_mesh)
    garbage = tmp_path / "garbage.bin"
    garbage.write_bytes(b"\x00" * 64)
    with pytest.raises(lambert.InputError, match="garbage.bin"):
        lambert.load_form_factors(garbage, cornell_mesh)
    assert issubclass(lambert.InputError, lambert.Error)


def test_wrong_arguments_raise_not_crash(cornell_mesh):
    n = len(cornell_mesh)
    F = sp.identity(n, format="csr") * 0.0
    with pytest.raises(lambert.UsageError):
        lambert.form_factors(cornell_mesh, estimator="nope")
    with pytest.raises(lambert.UsageError):
        lambert.form_factors(cornell_mesh, estimator="gather", samples=4)
    # Issue 33, item 8: nan passed `threshold < 0` and dropped nothing; the hemicube never
    # read samples.
    for bad in (float("nan"), -0.1, 1.5):
        with pytest.raises(lambert.UsageError, match="threshold"):
            lambert.form_factors(cornell_mesh, estimator="hemicube", threshold=bad)
    with pytest.raises(lambert.UsageError, match="samples does not apply"):
        lambert.form_factors(cornell_mesh, estimator="hemicube", samples=4)
    with pytest.raises(TypeError):
        lambert.form_factors("not a mesh")
    with pytest.raises(TypeError):
        lambert.form_factors(cornell_mesh, samples=1.5)
    with pytest.raises(TypeError):
        lambert.solve(cornell_mesh, np.zeros((n, n)))
    with pytest.raises(lambert.UsageError, match="shape"):
        lambert.solve(cornell_mesh, sp.identity(n + 1, format="csr"))
    with pytest.raises(lambert.UsageError):
        lambert.solve(cornell_mesh, F, solver="nope")
    with pytest.raises(lambert.UsageError, match="shape"):
        lambert.vertex_radiosity(cornell_mesh, np.zeros((n, 2)))
    with pytest.raises(lambert.UsageError, match="shape"):
        lambert.render(cornell_mesh, np.zeros(n))
    with pytest.raises((TypeError, lambert.UsageError)):
        lambert.vertex_radiosity(cornell_mesh, "abc")
    with pytest.raises(lambert.UsageError):
        lambert.render(cornell_mesh, np.zeros((n, 3)), eye=(1, 2))
    with pytest.raises(lambert.UsageError, match="not finite"):
        bad = sp.csr_matrix(([np.nan], ([0], [1])), shape=(n, n))
        lambert.solve(cornell_mesh, bad)
    assert issubclass(lambert.UsageError, ValueError)


# Regression (issue 33, item 5): an F whose indptr is not monotone corrupted the heap in
# lambert.solve (free(): invalid size) or leaked a RuntimeError; now a UsageError, from the
# Python checks and, below them, from the extension's own (called directly).
def test_non_monotone_indptr_is_a_usage_error(cornell_mesh):
    import lambert._lambert as ext
    n = len(cornell_mesh)
    F = sp.csr_matrix((np.full(3, 0.1), ([0, 1, 2], [1, 2, 0])), shape=(n, n))
    for bad in ((3, 1), (2, 0)):  # indptr[1], indptr[2]: decreasing
        G = F.copy()
        G.indptr[1], G.indptr[2] = bad
        with pytest.raises(lambert.UsageError, match="indptr"):
            lambert.solve(cornell_mesh, G)
    indptr = F.indptr.astype(np.int64).copy()
    indices = F.indices.astype(np.int64)
    indptr[1], indptr[2] = 3, 1  # row 0 would run past row 1's start
    with pytest.raises(lambert.UsageError, match="indptr"):
        ext.solve(cornell_mesh, indptr, indices, F.data.astype(np.float64),
                  {"max_iterations": 100}, 1, None, {}, None, None)


def test_medium_solve_equals_the_cli(tmp_path, cornell):
    fog = ["--medium-box", "0,0,0,556,548.8,559.2", "--sigma-a", "0.001,0.001,0.001",
           "--voxels", 4, "--medium-rays", 64]
    run_cli("solve", "--patches", 150, "--estimator", "hybrid", "--samples", 4, "--seed", 3,
            "--tol", 1e-10, "-q", *fog, "-o", tmp_path / "B.csv")
    mesh = cornell.mesh(patches=150)
    F = lambert.form_factors(mesh, estimator="hybrid", samples=4, seed=3)
    B, report = lambert.solve(mesh, F, tol=1e-10, medium_box=(0, 0, 0, 556, 548.8, 559.2),
                              sigma_a=(1e-3,) * 3, voxels=4, medium_rays=64, seed=3)
    assert report["status"] == "converged" and report["medium"]["zones"] == 64
    import csv
    with open(tmp_path / "B.csv") as f:
        cli = np.array([[float(r[c]) for c in "RGB"] for r in csv.DictReader(f)])
    # The CSV holds 17 significant digits: a double read back is the double written.
    assert B.shape == cli.shape and np.array_equal(B, cli)
    for c in range(3):  # the medium takes its share of the absorbed power
        e = report["energy"][c]
        assert report["medium"]["absorbed_medium"][c] > 0
        assert math.isclose(report["medium"]["absorbed_medium"][c]
                            + report["medium"]["absorbed_surfaces"][c], e["absorbed"],
                            rel_tol=1e-9)
    with pytest.raises(lambert.UsageError):
        lambert.solve(mesh, F, sigma_a=(1e-3,) * 3)  # coefficients without a box
    with pytest.raises(TypeError):
        lambert.solve(mesh, F, medium_bx=(0, 0, 0, 1, 1, 1))


def test_hierarchical_equals_the_cli(tmp_path, cornell):
    run_cli("solve", "--method", "hierarchical", "--epsilon", 1e-3, "--seed", 2, "-q",
            "-o", tmp_path / "B.csv")
    leaves, B, report = lambert.solve_hierarchical(cornell, epsilon=1e-3, seed=2)
    assert report["status"] == "converged" and len(leaves) == report["leaves"] == len(B)
    import csv
    with open(tmp_path / "B.csv") as f:
        cli = np.array([[float(r[c]) for c in "RGB"] for r in csv.DictReader(f)])
    assert np.array_equal(B, cli)  # 17 significant digits in the CSV: exact
    assert max(e["relative_imbalance"] for e in report["energy"]) < 1e-9
    img = lambert.render(leaves, B, width=16, height=16, antialias=1)  # the leaf mesh renders
    assert img.max() > 0
    with pytest.raises(lambert.UsageError):
        lambert.solve_hierarchical(cornell, epsilon=2.0)


def test_long_calls_release_the_gil(cornell):
    import threading
    import time
    mesh = cornell.mesh(patches=600)
    ticks, done = [0], threading.Event()

    def tick():
        while not done.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    t = threading.Thread(target=tick)
    t.start()
    start = time.perf_counter()
    lambert.form_factors(mesh, estimator="hybrid", samples=8)
    seconds = time.perf_counter() - start
    done.set()
    t.join()
    # Holding the GIL for the whole call would leave the ticker at 0 or 1 (it gets the
    # interpreter only before and after); released, it ticks about once a millisecond
    # (a 20th of that on a loaded machine still passes).
    assert seconds < 0.05 or ticks[0] >= 50 * seconds, (ticks[0], seconds)


def thermal_box(tmp_path):
    """The STL worked example (data/thermal_box): its path, the conditions of its three
    surfaces and the --surfaces file holding them."""
    import json
    stl = os.path.join(os.path.dirname(__file__), "..", "..", "data", "thermal_box",
                       "thermal_box.stl")
    conditions = {"heater": {"emissivity": 0.9, "temperature": 800},
                  "cold_plate": {"emissivity": 0.8, "temperature": 300},
                  "walls": {"emissivity": 0.5, "heat_flux": 0}}
    surfaces_file = tmp_path / "surfaces.json"
    surfaces_file.write_text(json.dumps(conditions))
    return stl, conditions, surfaces_file


def test_heat_equals_the_cli_on_the_stl_example(tmp_path):
    """lambert.heat on the STL worked example gives the CLI's per-patch Q bit for bit (the
    same F: form_factors equals the CLI's; the same system and solver), and the closure
    (sum of Q + environment power) is at rounding level."""
    stl, conditions, surfaces_file = thermal_box(tmp_path)
    run_cli("heat", stl, "--surfaces", surfaces_file, "--length-unit", "mm", "--patches", 200,
            "--estimator", "hybrid", "--samples", 8, "--seed", 5, "--tol", 1e-10, "-q",
            "-o", tmp_path / "h")
    scene = lambert.load_scene(stl)  # an STL, told apart by content
    assert sorted(scene.surfaces) == ["cold_plate", "heater", "walls"]
    mesh = scene.mesh(patches=200)
    F = lambert.form_factors(mesh, estimator="hybrid", samples=8, seed=5)
    r = lambert.heat(mesh, F, conditions, length_unit="mm", tol=1e-10)
    assert r["status"] == "converged"
    import csv
    with open(tmp_path / "h_patches.csv") as f:
        cli_Q = np.array([float(row["Q_W"]) for row in csv.DictReader(f)])
    # The CSV holds 17 significant digits: a double read back is the double written.
    assert np.array_equal(r["Q"], cli_Q)
    # Closure: with a reciprocal F (hybrid is a pair estimator) sum Q + environment = 0
    # identically; summing ~200 terms of up to ~10 kW rounds at 1e-16 * 200 * 1e4 ~ 2e-10 W.
    total = sum(abs(q) for q in r["Q"])
    assert abs(r["closure"]) <= 1e-12 * total
    by_name = {s["name"]: s for s in r["surfaces"]}
    assert by_name["heater"]["Q"] > 0 > by_name["cold_plate"]["Q"]
    # The re-radiating walls: q = 0 to the solver's tolerance, T between the two plates'.
    assert abs(by_name["walls"]["Q"]) <= 1e-6 * by_name["heater"]["Q"]
    assert 300 < by_name["walls"]["T"] < 800
    with pytest.raises(lambert.InputError):  # a surface the scene does not have
        lambert.heat(mesh, F, {"floor": {"emissivity": 0.5, "temperature": 300}})
    with pytest.raises(lambert.UsageError):
        lambert.heat(mesh, F, conditions, length_unit="furlong")
    with pytest.raises(TypeError):
        lambert.heat(mesh, F, [("heater", 800)])


def test_heat_conductors_equal_the_cli_and_are_reciprocal(tmp_path):
    """lambert.heat(conductors=True) gives `lambert heat --conductors`' matrix bit for bit
    (the same F and solver; the CSV holds 17 significant digits), GR is symmetric to the
    conductor solves' tolerance (1e-10 relative: each J^(S) is solved to it), and each row
    plus its environment share is eps A (every emitted watt ends somewhere)."""
    import csv
    stl, conditions, surfaces_file = thermal_box(tmp_path)
    run_cli("heat", stl, "--surfaces", surfaces_file, "--length-unit", "mm", "--patches", 120,
            "--estimator", "hybrid", "--samples", 8, "--seed", 5, "--tol", 1e-10, "-q",
            "-o", tmp_path / "h.csv", "--conductors", tmp_path / "gr.csv")
    mesh = lambert.load_scene(stl).mesh(patches=120)
    F = lambert.form_factors(mesh, estimator="hybrid", samples=8, seed=5)
    r = lambert.heat(mesh, F, conditions, length_unit="mm", tol=1e-10, conductors=True)
    c = r["conductors"]
    with open(tmp_path / "gr.csv") as f:
        rows = list(csv.reader(f))
    assert rows[0][1:-1] == c["surfaces"]
    cli = np.array([[float(v) for v in row[1:-1]] for row in rows[1:]])
    assert np.array_equal(cli, c["GR_m2"])
    assert np.array_equal(np.array([float(row[-1]) for row in rows[1:]]), c["environment_m2"])
    GR = c["GR_m2"]
    assert np.abs(GR - GR.T).max() <= 1e-9 * np.abs(GR).max()
    assert np.allclose(GR.sum(axis=1) + c["environment_m2"], c["emittance_m2"], rtol=1e-9)
    assert "conductors" not in lambert.heat(mesh, F, conditions, length_unit="mm")


def test_heat_isothermal_enclosure_has_no_net_flux(tmp_path):
    """Every surface of a closed cube at the same T: J* = sigma T^4 solves the system when the
    rows of F sum to 1, so every q = J - H is 0 up to F's and the solver's errors. Rows of the
    analytic F are off by at most n tol_f; the solve's |J - J*| <= (n tol_f sigma T^4 + tol
    ||E||_2) / (1 - rho) (||K^-1|| <= 1/(1 - rho), ||E||_2 <= sqrt(n) sigma T^4), and H = F J
    adds as much again plus the row error itself: |q| <= 4 (n tol_f + tol sqrt(n)) sigma T^4 /
    (1 - rho)."""
    faces = cube_faces()
    mesh = lambert.load_scene(write_obj(tmp_path / "cube.obj", faces)).mesh(max_edge=0.5)
    n = len(mesh)
    tol_f, tol, eps, T = 1e-9, 1e-12, 0.7, 500.0
    F = lambert.form_factors(mesh, estimator="analytic", tol=tol_f)
    r = lambert.heat(mesh, F, {"*": {"emissivity": eps, "temperature": T}}, tol=tol)
    sigma_t4 = 5.670374419e-8 * T ** 4
    bound = 4 * (n * tol_f + tol * math.sqrt(n)) * sigma_t4 / eps
    assert r["status"] == "converged"
    assert np.abs(r["q"]).max() <= bound
    assert np.abs(r["J"] - sigma_t4).max() <= bound


def test_ctrl_c_stops_a_long_call_within_seconds(cornell):
    """Issue 33, item 8: Ctrl-C during a long call waited for its end (Python handles SIGINT
    only with the GIL back). The call below is minutes of work; SIGINT half a second in must
    end it with KeyboardInterrupt within a few seconds, and the next call runs normally."""
    import signal
    import threading
    import time
    mesh = cornell.mesh(patches=3000)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        lambert.form_factors(mesh, estimator="mc", samples=256)  # ~1e9 rays
    timer.join()
    # The parallel loops stop at their next chunk: well under the minutes the call needs
    # (20 s of slack for a loaded 2-core machine).
    assert time.monotonic() - start < 20
    small = cornell.mesh(patches=40)
    F = lambert.form_factors(small, estimator="hybrid", samples=4)
    assert F.shape == F.matrix.shape == (len(small), len(small))


def test_keywords_are_checked_and_documented_from_the_declarations(cornell_mesh):
    """The declared options (pipeline/option_specs.hpp) reach Python: each keyword of
    form_factors and solve is in help() with its range and default, its signature default is
    the declared one, and a value outside the range is refused naming the keyword."""
    import inspect
    specs = {s["name"]: s for s in lambert.option_specs() if not s["commands"]}
    for fn, names in ((lambert.form_factors, ["--estimator", "--samples", "--rays", "--ff-tol",
                                              "--threshold", "--reciprocity", "--hemicube-res",
                                              "--specular-depth", "--specular-rays"]),
                      (lambert.solve, ["--solver", "--tol", "--max-iter", "--omega",
                                       "--preconditioner", "--restart"])):
        parameters = inspect.signature(fn).parameters
        for name in names:
            s = specs[name]
            assert s["keyword"] in parameters, (fn.__name__, name)
            assert f"    {s['keyword']} : " in fn.__doc__ and s["accepts"] in fn.__doc__
            default = parameters[s["keyword"]].default
            if default is None:  # None: the declared default applies
                continue
            if s["kind"] == "choice":
                assert default == s["default"], (name, default)
            else:
                assert float(default) == float(s["default"]), (name, default)
    with pytest.raises(lambert.UsageError, match=r"samples: 0 is not an integer in \[1, 1048576\]"):
        lambert.form_factors(cornell_mesh, estimator="hybrid", samples=0)
    F = lambert.form_factors(cornell_mesh, estimator="hybrid", samples=2)
    with pytest.raises(lambert.UsageError, match=r"omega: 2.5 is not a number in \[0.001, 1.999\]"):
        lambert.solve(cornell_mesh, F, solver="sor", omega=2.5)


def test_help_lists_every_estimator_parameter_with_its_range_from_the_registry(cornell_mesh):
    """help(lambert.form_factors) lists every parameter an estimator of the registry declares
    (geometry/formfactors/formfactors.cpp), each with its range, default and readers, without a
    hand-kept list: the declarations are the estimators' rows."""
    params = [s for s in lambert.option_specs() if not s["commands"] and s["estimators"]]
    assert {s["name"] for s in params} >= {"--samples", "--rays", "--ff-tol", "--hemicube-res"}
    readers = {s["name"]: s["estimators"] for s in params}
    assert sorted(readers["--samples"]) == ["hybrid", "mc"]
    assert readers["--ff-tol"] == ["analytic"]
    doc = lambert.form_factors.__doc__
    for s in params:
        entry = "\n".join(doc[doc.index(f"    {s['keyword']} : "):].split("\n")[:2])
        assert f"default {s['default']}" in entry, s["name"]
        assert f"Accepts {s['accepts']}" in entry, s["name"]
        assert "Read by the estimator" in entry, s["name"]
    assert "Accepts an integer in [1, 1048576]" in doc  # --samples, its range
    with pytest.raises(TypeError, match="unexpected keyword argument 'no_such_parameter'"):
        lambert.form_factors(cornell_mesh, no_such_parameter=1)


def test_form_factor_keywords_go_by_name_through_the_clis_checks(cornell_mesh):
    """The form-factor keywords reach the library by name and pass the CLI's checks: what the
    chosen estimator does not read is refused with the reader from the declarations, auto's
    pick and the specular options are checked against the mesh, and a keyword at its declared
    default counts as not given (as an option left off the command line)."""
    with pytest.raises(lambert.UsageError,
                       match=r"^reciprocity does not apply to estimator mc \(read by the "
                             r"estimators gather and hemicube\)$"):
        lambert.form_factors(cornell_mesh, estimator="mc", reciprocity="average")
    with pytest.raises(lambert.UsageError,
                       match="^specular_depth and specular_rays do not apply: the scene has no "
                             "mirror or glass surface"):
        lambert.form_factors(cornell_mesh, estimator="hybrid", samples=2, specular_depth=2)
    with pytest.raises(lambert.UsageError, match=r"^rays does not apply: estimator auto picks "
                                                 r"hybrid for \d+ patches"):
        lambert.form_factors(cornell_mesh, rays=64)
    # Defaults given explicitly are not "given": the same F as leaving them off.
    a = lambert.form_factors(cornell_mesh, estimator="mc", samples=2, seed=5)
    b = lambert.form_factors(cornell_mesh, estimator="mc", samples=2, seed=5, reciprocity="auto",
                             threshold=0.0, hemicube_resolution=128, specular_depth=8)
    assert (a.matrix != b.matrix).nnz == 0
    assert a.settings == b.settings


def test_solver_keywords_the_solver_does_not_read_are_refused(cornell_mesh):
    """solve's keywords go by name through `lambert solve`'s check: omega is the SOR
    factor, direct iterates nothing (no tol, no max_iterations), a preconditioner is for the
    Krylov solvers; at their declared defaults they count as not given."""
    F = lambert.form_factors(cornell_mesh, estimator="hybrid", samples=2)
    cases = [(dict(solver="jacobi", omega=1.2), r"^omega does not apply to solver jacobi \(read "
                                                r"by the solver sor\)$"),
             (dict(solver="direct", tol=1e-6), "^tol does not apply to solver direct"),
             (dict(solver="gauss-seidel", preconditioner="ilut"),
              "^preconditioner does not apply to solver gauss-seidel")]
    for kwargs, message in cases:
        with pytest.raises(lambert.UsageError, match=message):
            lambert.solve(cornell_mesh, F, **kwargs)
    a = lambert.solve(cornell_mesh, F, solver="direct")
    b = lambert.solve(cornell_mesh, F, solver="direct", tol=1e-8, omega=1.5)
    assert np.array_equal(a.B, b.B)


def test_sky_and_sun_as_the_cli(tmp_path):
    # Two facing unit squares 1 apart (z up) under a sky of radiance 1: each escapes to the
    # sky with 1 - F, F = 0.19982, so B = rho pi (1 - F) / (1 - rho F) by symmetry. F from the
    # analytic estimator to 1e-9: far below the 1e-6 asked.
    bottom = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
    top = [(0, 0, 1), (0, 1, 1), (1, 1, 1), (1, 0, 1)]
    path = write_obj(tmp_path / "plates.obj", {"bottom": [bottom], "top": [top]},
                     {"bottom": ((0.5,) * 3, (0,) * 3), "top": ((0.5,) * 3, (0,) * 3)})
    mesh = lambert.load_scene(path).mesh()
    ff = lambert.form_factors(mesh, estimator="analytic", tol=1e-9)
    B, report = lambert.solve(mesh, ff, sky=(1, 1, 1))
    F, rho = parallel_squares_factor(1.0, 1.0), 0.5
    expected = rho * math.pi * (1 - F) / (1 - rho * F)
    assert np.allclose(B, expected, rtol=1e-6), (B, expected)
    assert report["daylight"]["sky_radiance"] == [1.0, 1.0, 1.0]
    # The sun straight down lights the top plate's back only: nothing reaches the faces.
    B_sun, _ = lambert.solve(mesh, ff, sun=(0, 0, -1, 100, 100, 100))
    assert np.all(B_sun == 0.0)
    # From below it is hidden from the top plate's face by the bottom plate, but at 2 across
    # for 1 up its rays pass beside it: the top plate is lit whole with H = S / sqrt(5), the
    # bottom plate (the sun behind it) only by the top, so B_top = rho H / (1 - rho^2 F^2).
    B_up, _ = lambert.solve(mesh, ff, sun=(0, 0, 1, 100, 100, 100), tol=1e-12)
    assert np.all(B_up == 0.0)
    B_side, _ = lambert.solve(mesh, ff, sun=(2, 0, 1, 100, 100, 100), tol=1e-12)
    t = mesh.surface_ids == mesh.surface_names.index("top")
    H = 100 / math.sqrt(5)
    assert np.allclose(B_side[t], rho * H / (1 - rho * rho * F * F), rtol=1e-9)
    with pytest.raises(lambert.UsageError, match="no length"):
        lambert.solve(mesh, ff, sun=(0, 0, 0, 1, 1, 1))
    with pytest.raises(lambert.UsageError, match="sky"):
        lambert.solve(mesh, ff, sky=(1, -1, 1))
    with pytest.raises(ValueError, match="3 components"):
        lambert.solve(mesh, ff, sky=(1, 1))
    # The picture: rays that miss see the sky's radiance.
    img = lambert.render(mesh, B, eye=(0.5, -3, 0.5), look_at=(0.5, 0.5, 0.5), up=(0, 0, 1),
                         width=16, height=16, antialias=1, sky=(1, 2, 3))
    assert np.allclose(img[0, 0], [1, 2, 3])


def read_glb(path):
    """A minimal GLB reader (the container, the JSON, float and uint32 accessors): the JSON and
    a dict of the first primitive's attributes as numpy arrays."""
    import json
    import struct
    data = open(path, "rb").read()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert (magic, version, length) == (b"glTF", 2, len(data))
    json_length, = struct.unpack_from("<I", data, 12)
    doc = json.loads(data[20:20 + json_length])
    bin_start = 20 + json_length + 8
    arrays = {}
    for name, index in doc["meshes"][0]["primitives"][0]["attributes"].items():
        a = doc["accessors"][index]
        view = doc["bufferViews"][a["bufferView"]]
        width = 3 if a["type"] == "VEC3" else 1
        arrays[name] = np.frombuffer(data, np.float32, a["count"] * width,
                                     bin_start + view["byteOffset"]).reshape(a["count"], width)
    return doc, arrays


def test_write_glb_splits_the_solution_by_light_source(cornell_mesh, tmp_path):
    # The light and a sky: the glb holds the solution (COLOR_0, the conservative vertex field
    # of B in float32) and one basis per source; they sum to it within kLinearityTolerance
    # (1e-6 of the largest value; pipeline/relight.hpp derives it).
    ff = lambert.form_factors(cornell_mesh, estimator="hybrid", samples=8, seed=1)
    sol = lambert.solve(cornell_mesh, ff, sky=(0.3, 0.3, 0.4))
    info = lambert.write_glb(tmp_path / "b.glb", cornell_mesh, sol.B, ff, sky=(0.3, 0.3, 0.4))
    assert sorted(info["light_sources"]) == ["light", "sky"]
    assert info["linearity_error"] <= 1e-6
    doc, arrays = read_glb(tmp_path / "b.glb")
    field = lambert.vertex_radiosity(cornell_mesh, sol.B)
    assert np.array_equal(arrays["COLOR_0"], np.asarray(field.values, np.float32))
    total = arrays["COLOR_1"].astype(float) + arrays["COLOR_2"]
    assert np.abs(total - arrays["COLOR_0"]).max() <= 1e-6 * np.abs(arrays["COLOR_0"]).max()
    extras = doc["asset"]["extras"]["lambert"]
    assert extras["sky_radiance"] == [0.3, 0.3, 0.4]
    assert [e["name"] for e in extras["emitters"]] == info["light_sources"]
    # Without F: the solution alone, and why.
    info = lambert.write_glb(tmp_path / "c.glb", cornell_mesh, sol.B)
    assert info["light_sources"] == []
    doc, arrays = read_glb(tmp_path / "c.glb")
    assert set(arrays) == {"POSITION", "NORMAL", "COLOR_0"}
    assert "F=F" in doc["asset"]["extras"]["lambert"]["no_relighting"]


def test_show_writes_the_viewer_page_of_a_solution(cornell_mesh, tmp_path):
    ff = lambert.form_factors(cornell_mesh, estimator="hybrid", samples=8, seed=1)
    sol = lambert.solve(cornell_mesh, ff)
    page = lambert.show(sol, path=tmp_path / "view" / "index.html", open=False)
    assert page == str(tmp_path / "view" / "index.html")
    html = open(page).read()
    assert "window.LAMBERT_GLB_BASE64" in html and "LAMBERT_THREE" in html
    doc, arrays = read_glb(tmp_path / "view" / "index.glb")
    assert [e["name"] for e in doc["asset"]["extras"]["lambert"]["emitters"]] == ["light"]
    with pytest.raises(lambert.UsageError, match="mesh"):
        lambert.show(sol.B, open=False)


def test_mesh_surface_floor_is_the_clis(cornell):
    # Issue 35: under a patch target every surface gets at least `surface_floor` patches, the
    # CLI's --surface-floor: the light (a 1.4 % share of 2,000 patches, 12) is raised to 32
    # or more, the mesh is the CLI's patch for patch, and the floor is refused where a mesh
    # would not read it (an edge bound, discontinuity meshing, no target).
    default = cornell.mesh(patches=2000)
    light = default.surface_names.index("light")
    raised = cornell.mesh(patches=2000, surface_floor=32)
    assert (default.surface_ids == light).sum() < 32 <= (raised.surface_ids == light).sum()
    out = run_cli("info", "--patches", 2000, "--surface-floor", 32)
    assert f"patches: {len(raised)} " in out.stdout
    for bad in ({"max_edge": 50.0, "patches": 100}, {"discontinuity": True, "patches": 100}, {}):
        with pytest.raises(lambert.UsageError):
            cornell.mesh(surface_floor=8, **bad)


def test_target_stderr_is_the_clis(tmp_path, cornell):
    # Issue 36: --target-stderr samples each pair until both its factors' standard errors are
    # at most the target: the keyword gives the CLI's F bit for bit, every stored error is
    # within the target, and an estimator that does not read it refuses it.
    mesh = cornell.mesh(patches=60)
    ff = lambert.form_factors(mesh, estimator="hybrid", samples=4, target_stderr=2e-3,
                              stderr=True, seed=3)
    assert ff.stderr.max() <= 2e-3 and ff.stats["pairs_short_of_target"] == 0
    plain = lambert.form_factors(mesh, estimator="hybrid", samples=4, stderr=True, seed=3)
    assert plain.stderr.max() > 2e-3 and ff.stats["rays"] > plain.stats["rays"]
    cli = tmp_path / "F.bin"
    run_cli("formfactors", "--patches", 60, "--estimator", "hybrid", "--samples", 4,
            "--target-stderr", 2e-3, "--stderr", "--seed", 3, "-q", "-o", cli)
    G = lambert.load_form_factors(cli, mesh).matrix
    assert ff.matrix.data.tobytes() == G.data.tobytes()
    with pytest.raises(lambert.UsageError, match="target_stderr does not apply"):
        lambert.form_factors(mesh, estimator="gather", target_stderr=1e-3)
