"""lambert: radiosity and form factors from Python.

    import lambert
    scene = lambert.load_scene()                 # the built-in Cornell box
    mesh = scene.mesh(patches=500)
    ff = lambert.form_factors(mesh, estimator="hybrid", samples=32, seed=1)  # ff.matrix: CSR
    B, report = lambert.solve(mesh, ff, solver="gauss-seidel", tol=1e-8)

Errors: lambert.InputError (a bad scene or F file: SceneError/IoError, the file named in the
message), lambert.UsageError (a bad argument; also a ValueError), both lambert.Error.
Wrong array shapes raise UsageError, wrong types TypeError.

Arrays: Mesh arrays are read-only views into the C++ mesh (no copy; `patch_corners` is a
copy). Results (F's data, B, images) are handed over without a copy; scipy converts F's
64-bit indices to 32-bit (a copy of the index arrays) when they fit. Arrays passed in (F, B)
are copied into lambert's types.
"""

import os as _os

import numpy as _np
import scipy.sparse as _sparse

# An installed package (`pip install .`) carries the built-in Cornell box: the engine reads it
# there unless LAMBERT_DATA_DIR names another folder (a build tree reads the source's data/).
_data = _os.path.join(_os.path.dirname(__file__), "data")
if _os.path.isdir(_data):
    _os.environ.setdefault("LAMBERT_DATA_DIR", _data)

from . import _lambert  # noqa: E402
from ._lambert import Error, InputError, UsageError, Mesh, Scene, VertexField  # noqa: F401,E402

__all__ = [
    "__version__", "Error", "InputError", "UsageError", "Scene", "Mesh", "VertexField",
    "FormFactors", "Solution", "load_scene",
    "form_factors", "save_form_factors", "load_form_factors", "solve", "solve_hierarchical", "heat",
    "vertex_radiosity",
    "write_vertex_exr", "render", "write_glb", "show", "estimators", "solvers", "set_verbosity", "option_specs",
]

__version__ = _lambert.__version__  # the project's one version (CHANGELOG.md, "Version scheme")
estimators = _lambert.estimators
solvers = _lambert.solvers
set_verbosity = _lambert.set_verbosity


def load_scene(path=None, strict=False, emit=None):
    """Loads an OBJ, STL or PLY scene, told apart by content (None: the built-in Cornell box).
    `emit` maps a surface or material
    glob to an emission (R, G, B), as the CLI's --emit. Raises InputError for a bad file."""
    if path is None:
        path = _lambert.builtin_cornell_box_path()
    rules = [(str(k), [float(x) for x in v]) for k, v in (emit or {}).items()]
    return _lambert.load_scene(str(path), bool(strict), rules)


def _mesh(self, max_edge=None, patches=None, discontinuity=False, surface_floor=None):
    """Meshes the scene: patch edges at most `max_edge` (scene units) or about `patches`
    patches (max_edge wins when both are given); neither: one patch per face (triangulated
    above 4 corners). With `patches`, every surface gets at least `surface_floor` patches
    (default 4; the floors take at most a quarter of the target). The same mesh as the CLI's
    --max-edge/--patches/--surface-floor; `surface_floor` without `patches`, or with
    `discontinuity`, is a UsageError (it would not be read)."""
    if surface_floor is not None and (not patches or max_edge or discontinuity):
        raise UsageError("surface_floor is read only with patches (and without max_edge or "
                         "discontinuity)")
    floor = _lambert.default_surface_floor if surface_floor is None else int(surface_floor)
    return _lambert.mesh_scene(self, float(max_edge or 0.0), int(patches or 0), bool(discontinuity),
                               floor)


Scene.mesh = _mesh


def _csr(arrays, n):
    data, indices, indptr = arrays
    return _sparse.csr_matrix((data, indices, indptr), shape=(n, n), copy=False)


class FormFactors:
    """Form factors with what made them: the result of `form_factors` and `load_form_factors`.

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix, shape (N, N)
        F, row i the fractions of patch i's power that reach each other patch.
    stderr : scipy.sparse.csr_matrix or None
        Per-entry standard errors (the Monte Carlo estimators, or a file that kept them), or
        None.
    settings : str
        The settings text a saved F carries (estimator, samples, seed, ...): what made it.
    stats : dict or None
        What the computation did (rays, pairs tested and culled, seconds); None when loaded.
    mesh_hash : int
        The hash of the mesh F belongs to (`Mesh.hash`): a saved F is refused on another mesh.

    `solve`, `heat` and `save_form_factors` take a FormFactors or a plain scipy matrix. Derived
    matrices (``ff.matrix * 2``) are plain scipy matrices: they no longer claim the settings.
    """

    def __init__(self, matrix, stderr, settings, stats, mesh_hash):
        self.matrix = matrix
        self.stderr = stderr
        self.settings = settings
        self.stats = stats
        self.mesh_hash = mesh_hash

    @property
    def shape(self):
        """(N, N)."""
        return self.matrix.shape

    def __repr__(self):
        n = self.matrix.shape[0]
        return (f"<lambert.FormFactors {n}x{n}, {self.matrix.nnz} entries, "
                f"stderr={'yes' if self.stderr is not None else 'no'}, settings={self.settings!r}>")


class Solution(tuple):
    """A solve's result, (B, report), which unpacks as a pair.

    Attributes
    ----------
    B : numpy.ndarray, shape (N, 3)
        Radiosity per patch and channel (W/m^2).
    report : dict
        status, iterations, residual, seconds, per channel ``channels`` and ``energy``, and the
        solver settings used (``solver``, ``tol``, ...).
    """

    def __new__(cls, B, report):
        return super().__new__(cls, (B, report))

    @property
    def B(self):
        return self[0]

    @property
    def report(self):
        return self[1]

    def __repr__(self):
        return (f"<lambert.Solution {self[0].shape[0]} patches, status {self[1].get('status')!r}>")


def _wrap_ff(result, mesh, computed):
    n = len(mesh)
    S = None if result.get("stderr") is None else _csr(result["stderr"], n)
    return FormFactors(_csr(result["F"], n), S, result.get("settings", ""),
                       result.get("stats") if computed else None, mesh.hash)


def form_factors(mesh, estimator="auto", samples=None, rays=None, seed=1, threads=0,
                 threshold=0.0, reciprocity="auto", tol=None, hemicube_resolution=128,
                 specular_depth=8, specular_rays=1024, stderr=False, **estimator_params):
    """The form factors of the mesh, as a `FormFactors` (matrix, stderr, settings, stats).

    The keywords are the CLI's options (docs/options.md) with the same values, ranges and
    defaults; the same settings give the CLI's F bit for bit. A keyword set to a value other
    than its default that the estimator does not read is refused (UsageError), as on the
    command line.

    Parameters
    ----------
    mesh : Mesh
        The patches (``scene.mesh(...)``).
@declared --estimator @estimator-parameters --threshold --reciprocity --specular-depth --specular-rays
    seed : int, default 1
        The random seed: the same seed gives the same F whatever ``threads`` is.
    threads : int, default 0
        Worker threads (0: all cores).
    stderr : bool, default False
        Keep the per-entry standard errors of the Monte Carlo estimators (``.stderr``).
    **estimator_params
        The parameters of estimators registered beyond those above (listed above with
        theirs), by keyword.

    Returns
    -------
    FormFactors
    """
    _check_mesh(mesh)
    # By name, what the CLI would call given: a keyword whose default is None when set, the
    # others when they differ from their declared default.
    optional = dict(samples=_opt_int(samples, "samples"), rays=_opt_int(rays, "rays"),
                    tol=None if tol is None else float(tol))
    defaulted = dict(estimator=str(estimator), threshold=float(threshold),
                     reciprocity=str(reciprocity),
                     hemicube_resolution=_int(hemicube_resolution, "hemicube_resolution"),
                     specular_depth=_int(specular_depth, "specular_depth"),
                     specular_rays=_int(specular_rays, "specular_rays"))
    for keyword, value in estimator_params.items():  # checked by their declarations
        spec = _KEYWORD_SPECS.get(("form factors", keyword))
        if spec is None or not spec["estimators"] or keyword in optional:
            raise TypeError(f"form_factors() got an unexpected keyword argument '{keyword}'")
        if value is not None:
            optional[keyword] = (_int(value, keyword) if spec["kind"] == "integer"
                                 else float(value))
    settings = {k: v for k, v in optional.items() if v is not None}
    settings.update({k: v for k, v in defaulted.items()
                     if not _is_default("form factors", k, v)})
    result = _lambert.form_factors(mesh, settings, _int(seed, "seed"), _int(threads, "threads"),
                                   bool(stderr))
    return _wrap_ff(result, mesh, computed=True)


def save_form_factors(path, mesh, F, stderr=None, precision="double"):
    """Saves F as the CLI does: Matrix Market for a .mtx path, else lambert's binary format
    (with the standard errors when known), tied to the mesh. F is a `FormFactors` (its
    settings, and in the binary format its standard errors, are saved with it) or a scipy
    matrix (then `stderr` may give the errors, and no settings are recorded)."""
    _check_mesh(mesh)
    settings = ""
    if isinstance(F, FormFactors):
        if stderr is None and not str(path).endswith(".mtx"):  # Matrix Market holds F alone
            stderr = F.stderr
        settings = F.settings
    indptr, indices, data = _csr_arrays(F, mesh, "F")
    err = None
    if stderr is not None:
        s_indptr, s_indices, s_data = _csr_arrays(stderr, mesh, "stderr")
        err = (s_data, s_indices, s_indptr)
    _lambert.save_form_factors(str(path), mesh, indptr, indices, data, err, settings, str(precision))


def load_form_factors(path, mesh):
    """Reads an F saved by the CLI or save_form_factors (binary or Matrix Market) as a
    `FormFactors` (its standard errors when the file kept them, its settings text); refuses
    (InputError) one made for another mesh."""
    _check_mesh(mesh)
    return _wrap_ff(_lambert.load_form_factors(str(path), mesh), mesh, computed=False)


_MEDIUM_KEYS = ("medium_box", "sigma_a", "sigma_s", "medium_emission", "medium_grid", "voxels",
                "voxel_size", "medium_rays", "transmittance_samples", "seed")


def solve(mesh, F, solver="gauss-seidel", tol=1e-8, max_iterations=10000, omega=1.5,
          preconditioner="diagonal", restart=30, threads=1, initial_guess=None, sky=None,
          sun=None, **medium):
    """Solves (I - rho F) B = E per channel.

    Parameters
    ----------
    mesh : Mesh
    F : FormFactors or scipy.sparse matrix
@declared --solver --tol --max-iter --omega --preconditioner --restart
    threads : int, default 1
        Threads for the products with F (Gauss-Seidel, SOR and Southwell sweep in order).
    initial_guess : array (N, 3), optional
        A warm start for the iterative solvers (default: E).
    sky : (R, G, B), optional
        A uniform sky of this radiance (W m^-2 sr^-1) on every direction that escapes the
        scene, as the CLI's --sky: each patch gets pi L (1 - sum_j F_ij).
    sun : (DX, DY, DZ, R, G, B), optional
        A sun, as the CLI's --sun: light travelling along (DX, DY, DZ) with irradiance R, G, B
        (W/m^2) on a surface facing it; each patch's lit share from 16 x 16 shadow rays.
        With either, report["daylight"] holds the power each brings.
    **medium
        A participating medium (the CLI's solve --medium-box ...): medium_box=(x0, y0, z0,
        x1, y1, z1) with sigma_a, sigma_s, medium_emission (R, G, B), voxels or voxel_size,
        or medium_grid=FILE; medium_rays, transmittance_samples and seed steer its exchange
        factors. F is then the surfaces' F; B holds the patches' rows and report["medium"]
        the medium's part (zones, absorbed_medium per channel, ...).

    Returns
    -------
    Solution
        (B, report), which unpacks as a pair: B an (N, 3) array, report a dict with status,
        iterations, residual (worst channel), seconds, and per channel ``channels``
        (residual_history, time_history, ...) and ``energy`` (emitted, absorbed, escaped,
        relative_imbalance).
    """
    _check_mesh(mesh)
    unknown = set(medium) - set(_MEDIUM_KEYS)
    if unknown:
        raise TypeError(f"solve() got unexpected keyword arguments {sorted(unknown)}")
    indptr, indices, data = _csr_arrays(F, mesh, "F")
    given = dict(solver=str(solver), tol=float(tol),
                 max_iterations=_int(max_iterations, "max_iterations"), omega=float(omega),
                 preconditioner=str(preconditioner), restart=_int(restart, "restart"))
    # By name, only what differs from the declared default (what the CLI calls given).
    settings = {k: v for k, v in given.items() if not _is_default("solver", k, v)}
    solution = Solution(*_lambert.solve(mesh, indptr, indices, data, settings,
                                        _int(threads, "threads"), initial_guess, medium,
                                        _daylight(sky, 3, "sky"), _daylight(sun, 6, "sun")))
    if not medium:  # what show() needs to split it by light source
        solution._problem = dict(mesh=mesh, F=F, sky=sky, sun=sun, solver=solver, tol=tol,
                                 max_iterations=max_iterations, omega=omega,
                                 preconditioner=preconditioner, restart=restart)
    return solution


def heat(mesh, F, surfaces, ambient_temperature=0.0, length_unit="m", solver="gauss-seidel",
         tol=1e-8, max_iterations=10000, threads=1, conductors=False):
    """The CLI's `lambert heat` on a mesh and its view factors F: gray-diffuse radiative
    exchange. `surfaces` maps surface names (or "*") to {"emissivity": e, "temperature": T}
    (kelvin) or {"emissivity": e, "heat_flux": q} (W/m^2), as the --surfaces file;
    `length_unit` ("m", "cm", "mm", "in") the mesh's unit. Returns a dict: per patch T (K), J,
    H, q (W/m^2), Q (W) and area_m2 arrays; `surfaces` (name, area, T, T_min, T_max, J, q, Q);
    environment_power, closure (sum of Q + environment power: ~0), and the solver's report
    (status, iterations, residual, ...). With `conductors=True` also `conductors`, as
    `lambert heat --conductors` (docs/thermal.md): surfaces (names), GR_m2 (surfaces x
    surfaces radiative conductors eps_i A_i B_ij, m^2), environment_m2, emittance_m2 (eps A:
    each row of a closed enclosure sums to it), status and residual of its solves. Bad
    conditions raise InputError (naming the surface), bad arguments UsageError."""
    import json
    _check_mesh(mesh)
    if not isinstance(surfaces, dict):
        raise TypeError(f"surfaces must be a dict of surface name -> condition, got "
                        f"{type(surfaces).__name__}")
    indptr, indices, data = _csr_arrays(F, mesh, "F")
    given = dict(solver=str(solver), tol=float(tol),
                 max_iterations=_int(max_iterations, "max_iterations"))
    settings = {k: v for k, v in given.items() if not _is_default("solver", k, v)}
    return _lambert.heat(mesh, indptr, indices, data, json.dumps(surfaces),
                         float(ambient_temperature), str(length_unit), settings,
                         _int(threads, "threads"), bool(conductors))


def solve_hierarchical(scene, epsilon=None, min_area=0.0, link_rays=16, tol=1e-6,
                       max_iterations=1000, max_passes=10, seed=1, threads=0):
    """The CLI's --method hierarchical: refines links and elements of `scene` to the power
    error bound `epsilon` (default: the CLI's, 1e-5) and solves. Returns (leaves, B, report): the leaf Mesh (use it with
    vertex_radiosity, render, write_vertex_exr), B (leaves, 3), and the report (status,
    leaves, links, rays, passes, seconds, energy per channel, error_bound per leaf)."""
    if not isinstance(scene, Scene):
        raise TypeError(f"expected a lambert.Scene (load_scene(...)), got {type(scene).__name__}")
    if epsilon is None:
        epsilon = _lambert.default_hierarchical_epsilon
    return _lambert.solve_hierarchical(scene, float(epsilon), float(min_area),
                                       _int(link_rays, "link_rays"), float(tol),
                                       _int(max_iterations, "max_iterations"),
                                       _int(max_passes, "max_passes"), _int(seed, "seed"),
                                       _int(threads, "threads"))


def vertex_radiosity(mesh, B, mode="conservative"):
    """B (N, 3) interpolated to the shading vertices ("conservative" or "area"): a
    VertexField with positions, normals, surface_ids, patch_corners (views) and values."""
    _check_mesh(mesh)
    return _lambert.vertex_radiosity(mesh, B, str(mode))


def write_vertex_exr(path, mesh, B, mode="conservative", settings=""):
    """Writes the vertex EXR of the CLI's run/solve (-o B.exr) from B (N, 3)."""
    field = B if isinstance(B, VertexField) else vertex_radiosity(mesh, B, mode)
    _lambert.write_vertex_exr(str(path), mesh, field, str(settings))


def render(mesh, B, eye=None, look_at=None, up=None, fov=None, width=None, height=None,
           shading="gouraud", antialias=2, seed=1, threads=0, exr=None, png=None, ev=None,
           sky=None, sun=None, F=None, direct_rays=None):
    """Renders B (N, 3) with the scene's camera (or the given eye/look_at/up/fov/size):
    returns the linear radiance image, float32 (height, width, 3); also writes it as an EXR
    and/or a tone-mapped PNG (exposure `ev` stops, automatic when None) when paths are given.
    With the `sky` and `sun` that B was solved with (`solve`), rays that miss the scene see
    the sky and the sun is drawn per pixel with exact shadows (docs/scenes.md, Daylight).
    With `F`, the form factors B was solved with, the emitters' direct light is drawn per
    pixel with `direct_rays` shadow rays per sample (default 8; gouraud shading only, as
    `lambert run --direct-rays`, docs/rendering.md): crisp shadows over the vertex field of
    the rest."""
    _check_mesh(mesh)
    arrays = (None, None, None) if F is None else _csr_arrays(F, mesh, "F")
    vec = lambda v, name: None if v is None else [float(x) for x in _vec3(v, name)]  # noqa: E731
    return _lambert.render(mesh, B, vec(eye, "eye"), vec(look_at, "look_at"), vec(up, "up"),
                           None if fov is None else float(fov), _opt_int(width, "width"),
                           _opt_int(height, "height"), str(shading), _int(antialias, "antialias"),
                           _int(seed, "seed"), _int(threads, "threads"), str(exr or ""),
                           str(png or ""), None if ev is None else float(ev),
                           _daylight(sky, 3, "sky"), _daylight(sun, 6, "sun"), *arrays,
                           _opt_int(direct_rays, "direct_rays"))


def write_glb(path, mesh, B, F=None, sky=None, sun=None, ev=None, page=None, solver="gauss-seidel",
              tol=1e-8, max_iterations=10000, omega=1.5, preconditioner="diagonal", restart=30,
              threads=0):
    """Writes B (N, 3) on `mesh` as a glTF 2.0 binary file, as `lambert run`'s NAME.glb
    (docs/viewer.md): the shading-vertex mesh with the solution as COLOR_0, the patch edges and
    the scene's camera. With F (the form factors B was solved with, and the `sky`/`sun` it was
    solved under), also one COLOR_k per light source: the solution for that source alone,
    solved with the given solver settings (tolerance at most 1e-10), so that the viewer
    relights live. `ev` is the viewer's initial exposure (default: automatic). With `page`,
    also writes the viewer page there (one self-contained HTML file).

    Returns a dict: glb, page, light_sources (names, in COLOR_1... order), exposure_ev and,
    with F, linearity_error (how closely the bases sum to B, relative to its largest value)."""
    _check_mesh(mesh)
    arrays = (None, None, None) if F is None else _csr_arrays(F, mesh, "F")
    given = dict(solver=str(solver), tol=float(tol),
                 max_iterations=_int(max_iterations, "max_iterations"), omega=float(omega),
                 preconditioner=str(preconditioner), restart=_int(restart, "restart"))
    settings = {k: v for k, v in given.items() if not _is_default("solver", k, v)}
    page = "" if page is None else str(page)
    title = _os.path.splitext(_os.path.basename(str(path)))[0]
    return _lambert.write_viewer(mesh, B, *arrays, settings, _int(threads, "threads"),
                                 _daylight(sky, 3, "sky"), _daylight(sun, 6, "sun"),
                                 None if ev is None else float(ev), str(path), page, title)


def show(solution, mesh=None, F=None, path=None, open=True, **settings):
    """Writes the viewer page of a solution and opens it in the browser (docs/viewer.md):
    orbit and walk through the scene, one intensity slider per light source relighting it
    live. `solution` is what `solve` returned (it remembers its mesh, F, sky and sun), or B
    with `mesh` (and `F` for the sliders). `path`: the page to write (default: index.html in
    a new temporary folder, beside its .glb). `open=False` only writes. Other keywords go to
    write_glb (sky, sun, ev, solver settings). Returns the page's path."""
    import tempfile
    import webbrowser
    problem = dict(getattr(solution, "_problem", None) or {})
    B = solution.B if isinstance(solution, Solution) else solution
    if mesh is not None:
        problem["mesh"] = mesh
    if F is not None:
        problem["F"] = F
    if problem.get("mesh") is None:
        raise UsageError("show needs the mesh B lives on: show(solution) for what solve() "
                         "returned, else show(B, mesh=mesh, F=F)")
    problem.update(settings)
    if path is None:
        path = _os.path.join(tempfile.mkdtemp(prefix="lambert_view_"), "index.html")
    path = _os.path.abspath(str(path))
    _os.makedirs(_os.path.dirname(path), exist_ok=True)
    glb = _os.path.splitext(path)[0] + ".glb"
    mesh = problem.pop("mesh")
    write_glb(glb, mesh, B, page=path, **problem)
    if open:
        webbrowser.open("file://" + path)
    return path


def _daylight(value, n, name):
    if value is None:
        return None
    values = [float(x) for x in value]
    if len(values) != n:
        raise ValueError(f"{name} must have {n} components")
    return values


# --- the declared options' documentation (pipeline/option_specs.hpp) ---------------------------

_ALL_SPECS = _lambert.option_specs()
# The keywords' rows: those of every command (a command's own row, such as run's cheaper
# --samples, is the CLI's only).
_SPECS = {spec["name"]: spec for spec in _ALL_SPECS if not spec["commands"]}
_KEYWORD_SPECS = {(spec["group"], spec["keyword"]): spec for spec in _SPECS.values()
                  if spec["keyword"]}


def option_specs():
    """Every declared option of the CLI and these keywords (name, Python keyword, commands,
    group, kind, accepts, range or choices, default, what reads it, doc): the table they are
    checked and documented from, one row per meaning (``commands`` empty: every command)."""
    return [dict(spec) for spec in _ALL_SPECS]


def _is_default(group, keyword, value):
    """True when the keyword's value is its declared default (group: "form factors" for
    form_factors' keywords, "solver" for solve's: both have a `tol`)."""
    spec = _KEYWORD_SPECS[(group, keyword)]
    if spec["kind"] == "choice":
        return value == spec["default"]
    return float(value) == float(spec["default"])


def _readers(estimators):
    """'the estimator gather', 'the estimators hybrid and mc'."""
    names = (estimators[0] if len(estimators) == 1
             else ", ".join(estimators[:-1]) + " and " + estimators[-1])
    return ("the estimator " if len(estimators) == 1 else "the estimators ") + names


def _document_declared(function):
    """Replaces each ``@declared --name ...`` line of the docstring by numpydoc entries for
    those options, written from their declarations: keyword, kind, default, what it accepts
    and the description, the CLI option named."""
    lines = []
    for line in function.__doc__.split("\n"):
        if not line.startswith("@declared "):
            lines.append(line)
            continue
        names = []
        for name in line.split()[1:]:
            # Every estimator's parameters, as the registry declares them (one line each).
            names += ([n for n, spec in _SPECS.items() if spec["estimators"]]
                      if name == "@estimator-parameters" else [name])
        for name in names:
            spec = _SPECS[name]
            kind = {"integer": "int", "real": "float", "choice": "str", "flag": "bool",
                    "text": "str"}[spec["kind"]]
            lines.append(f"    {spec['keyword']} : {kind}, default {spec['default']}")
            readers = (f" Read by {_readers(spec['estimators'])}."
                       if spec["estimators"] else "")
            lines.append(f"        {spec['doc']}. Accepts {spec['accepts']} (the CLI's {name})."
                         + readers)
    function.__doc__ = "\n".join(lines)
    return function


form_factors = _document_declared(form_factors)
solve = _document_declared(solve)


# --- argument checks: wrong types raise TypeError, wrong shapes UsageError -------------------

def _check_mesh(mesh):
    if not isinstance(mesh, Mesh):
        raise TypeError(f"expected a lambert.Mesh (scene.mesh(...)), got {type(mesh).__name__}")


def _int(v, name):
    if isinstance(v, bool) or not isinstance(v, (int, _np.integer)):
        raise TypeError(f"{name} must be an integer, got {type(v).__name__}")
    return int(v)


def _opt_int(v, name):
    return None if v is None else _int(v, name)


def _vec3(v, name):
    a = _np.asarray(v, dtype=float)
    if a.shape != (3,):
        raise UsageError(f"{name} must have 3 components, got shape {a.shape}")
    return a


def _csr_arrays(F, mesh, name):
    if isinstance(F, FormFactors):
        if F.mesh_hash != mesh.hash:
            raise UsageError(f"{name} was made for another mesh (hash {F.mesh_hash:#x}, this "
                             f"mesh {mesh.hash:#x})")
        F = F.matrix
    if not _sparse.issparse(F):
        raise TypeError(f"{name} must be a scipy.sparse matrix, got {type(F).__name__}")
    n = len(mesh)
    if F.shape != (n, n):
        raise UsageError(f"{name} has shape {F.shape}, the mesh has {n} patches")
    F = F.tocsr()
    # indptr checked before scipy's own routines walk it (sum_duplicates trusts it).
    ip = _np.asarray(F.indptr)
    if (ip.ndim != 1 or len(ip) != n + 1 or ip[0] != 0 or ip[-1] != len(F.indices)
            or len(F.data) != len(F.indices) or (_np.diff(ip) < 0).any()):
        raise UsageError(f"{name}: indptr must run from 0 to nnz without decreasing")
    if not F.has_canonical_format:
        F = F.copy()
        F.sum_duplicates()
    return (F.indptr.astype(_np.int64, copy=False), F.indices.astype(_np.int64, copy=False),
            F.data.astype(_np.float64, copy=False))
