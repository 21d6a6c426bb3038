// The compiled part of `import lambert` (pybind11): scenes, meshes, form factors, solvers,
// vertex fields, rendering and the F files, over the library layers (core, geometry,
// solvers, io) and the radiosity problem of pipeline/problem. The pure-Python package
// (python/lambert/__init__.py) wraps these into the public API: scipy.sparse matrices are
// built there from the (data, indices, indptr) arrays handed out here.
//
// Arrays: mesh arrays are read-only views into the C++ mesh (zero-copy, strided over the
// patch structs where the values live in them), results moved out of C++ (F's CSR arrays,
// B, images) are owned by a capsule (zero-copy); arrays passed in are copied into the
// library's types. Long calls release the GIL.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <signal.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/render/render.hpp"
#include "geometry/render/vertex_field.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/array_args.hpp"
#include "io/exr.hpp"
#include "io/ff_file.hpp"
#include "io/heat_surfaces.hpp"
#include "io/json.hpp"
#include "io/obj_loader.hpp"
#include "io/stl_loader.hpp"
#include "io/tonemap.hpp"
#include "pipeline/daylight_stage.hpp"
#include "pipeline/heat_problem.hpp"
#include "pipeline/hierarchical_stage.hpp"
#include "pipeline/job.hpp"
#include "pipeline/medium_stage.hpp"
#include "pipeline/option_specs.hpp"
#include "pipeline/problem.hpp"
#include "pipeline/relight.hpp"
#include "pipeline/render_stages.hpp"
#include "pipeline/viewer_stage.hpp"
#include "solvers/gebhart.hpp"
#include "solvers/radiosity.hpp"

namespace py = pybind11;

namespace lambert {
namespace {

// A meshed scene with its BVH (built on first use, shared by form factors and renders).
// A LoadedScene, as the CLI's stages take it (pipeline/medium_stage reads one).
struct MeshHandle {
  LoadedScene loaded;
  const Scene& scene = loaded.scene;
  const PatchMesh& mesh = loaded.mesh;
  mutable std::mutex bvh_mutex;  // calls on one mesh from several Python threads (GIL released)
  const Bvh& get_bvh() const {
    const std::lock_guard<std::mutex> lock(bvh_mutex);
    return scene_bvh(loaded, 0);
  }
};

// A read-only numpy view of `count` rows of `cols` values of type T starting at `first`,
// rows `row_stride` bytes apart; `owner` keeps the memory alive.
template <typename T>
py::array view(const T* first, py::ssize_t count, py::ssize_t cols, py::ssize_t row_stride,
               py::handle owner) {
  std::vector<py::ssize_t> shape{count}, strides{row_stride};
  if (cols > 0) shape.push_back(cols), strides.push_back(sizeof(T));
  py::array a(py::dtype::of<T>(), shape, strides, first, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// The offset of a member inside a Patch (Patch holds Eigen members, so offsetof does not
// apply to it).
template <typename M>
py::ssize_t patch_offset(const Patch& p, const M& member) {
  return reinterpret_cast<const char*>(&member) - reinterpret_cast<const char*>(&p);
}

// Moves `v` to the heap and returns a numpy array over it, owned by a capsule.
template <typename T>
py::array_t<T> adopt(std::vector<T>&& v, std::vector<py::ssize_t> shape) {
  auto* heap = new std::vector<T>(std::move(v));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, heap->data(), owner);
}

py::array_t<double> adopt_matrix(const Eigen::MatrixX3d& m) {  // N x 3, row-major copy
  std::vector<double> v(static_cast<size_t>(m.rows()) * 3);
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (int c = 0; c < 3; ++c) v[3 * i + c] = m(i, c);
  return adopt(std::move(v), {m.rows(), 3});
}

py::array_t<double> adopt_dense(const Eigen::MatrixXd& m) {  // rows x cols, row-major copy
  std::vector<double> v(static_cast<size_t>(m.rows() * m.cols()));
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) v[i * m.cols() + j] = m(i, j);
  return adopt(std::move(v), {m.rows(), m.cols()});
}

using IndexArray = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
using ValueArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// A numpy array as the library's view of a caller's array (io/array_args.hpp).
template <typename T, typename A>
ArrayArg<T> arg(const A& a) {
  return {a.data(), std::vector<std::int64_t>(a.shape(), a.shape() + a.ndim())};
}

// An (N, 3) float64 array-like as an Eigen matrix; UsageError naming `what` otherwise.
Eigen::MatrixX3d matrix_n3(const ValueArray& a, std::int64_t n, const std::string& what) {
  return rows_of_three(arg<double>(a), n, what);
}

// A CSR matrix from its arrays, checked entry by entry (UsageError on any inconsistency).
SparseRowMatrix csr_from_arrays(std::int64_t n, const IndexArray& indptr, const IndexArray& indices,
                                const ValueArray& data, const std::string& what) {
  return lambert::csr_from_arrays(n, arg<std::int64_t>(indptr), arg<std::int64_t>(indices),
                                  arg<double>(data), what);
}

// (data, indices, indptr) of a compressed CSR matrix moved to the heap, zero-copy.
py::tuple csr_arrays(SparseRowMatrix&& F) {
  F.makeCompressed();
  auto* heap = new SparseRowMatrix();
  heap->swap(F);  // Eigen 3.4's SparseMatrix has no move
  py::capsule owner(heap, [](void* p) { delete static_cast<SparseRowMatrix*>(p); });
  const py::ssize_t n = heap->rows(), nnz = heap->nonZeros();
  return py::make_tuple(py::array_t<double>(nnz, heap->valuePtr(), owner),
                        py::array_t<std::int64_t>(nnz, heap->innerIndexPtr(), owner),
                        py::array_t<std::int64_t>(n + 1, heap->outerIndexPtr(), owner));
}

py::dict options_dict(const FormFactorOptions& o) {
  py::dict d;
  d["estimator"] = o.estimator;
  d["samples"] = o.pair.samples;
  d["rays"] = o.gather.rays;
  d["seed"] = o.run.seed;
  d["threshold"] = o.threshold;
  d["hemicube_resolution"] = o.hemicube.resolution;
  d["tol"] = o.analytic.tol;
  d["reciprocity"] = o.reciprocity;
  d["extended"] = o.contents.extended;
  for (const DeclaredEstimatorParam& p : estimator_params())  // those of later estimators
    if (!d.contains(p.param.keyword.c_str()))
      d[p.param.keyword.c_str()] = estimator_param(o, p.param.option);
  return d;
}

// The settings text stored with a saved F, as the CLI's formfactors command writes it.
std::string settings_text(const FormFactorOptions& o, const MeshHandle& m) {
  std::ostringstream ss;
  ss << format_ff_settings(o) << " patches=" << m.mesh.size() << " max_edge=" << m.mesh.max_edge;
  return ss.str();
}

py::dict ff_result(FormFactors&& ff, const MeshHandle& m) {
  py::dict out;
  out["settings"] = settings_text(ff.options, m);
  out["options"] = options_dict(ff.options);
  py::dict stats;
  stats["pairs_tested"] = ff.stats.pairs_tested;
  stats["pairs_culled"] = ff.stats.pairs_culled;
  stats["pairs_unverified"] = ff.stats.pairs_unverified;
  stats["pairs_short_of_target"] = ff.stats.pairs_short_of_target;
  stats["rays"] = ff.stats.rays;
  stats["seconds"] = ff.stats.seconds;
  out["stats"] = stats;
  const bool has_stderr = ff.stderr_F.rows() == ff.F.rows() && ff.F.rows() > 0;
  out["F"] = csr_arrays(std::move(ff.F));
  out["stderr"] = has_stderr ? py::object(csr_arrays(std::move(ff.stderr_F))) : py::none();
  if (ff.specular_continued.size() > 0)
    out["specular_continued"] =
        py::array_t<double>(ff.specular_continued.size(), ff.specular_continued.data());
  return out;
}

Eigen::Vector3d vec3(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) throw UsageError(std::string(what) + " must have 3 components");
  return {v[0], v[1], v[2]};
}

// The keywords sky=(R, G, B) and sun=(DX, DY, DZ, R, G, B) as the CLI's --sky and --sun, with
// their checks and messages.
Daylight daylight_from(const std::optional<std::vector<double>>& sky,
                       const std::optional<std::vector<double>>& sun) {
  Daylight light;
  if (sky) {
    if (sky->size() != 3) throw UsageError("sky must have 3 components (R, G, B)");
    for (double v : *sky) check_option_value(option_spec("--sky", "run"), v, "sky");
    light.sky = vec3(*sky, "sky");
  }
  if (sun) {
    std::string text;
    for (size_t k = 0; k < sun->size(); ++k) {
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.17g", (*sun)[k]);
      text += (k ? "," : "") + std::string(buf);
    }
    if (const std::string why = parse_sun(text, light); !why.empty())
      throw UsageError("sun: " + why);
  }
  return light;
}

// The scene's camera, or one framing it (the CLI's default view).
Camera default_camera(const Scene& scene) {
  if (scene.camera.defined) return scene.camera;
  const auto [lo, hi] = scene.bounds();
  return framing_camera(lo, hi);
}

double face_area(const Scene& s, const Face& f) {  // Newell's formula (planar polygon)
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < f.vertices.size(); ++k)
    n += s.vertices[f.vertices[k]].cross(s.vertices[f.vertices[(k + 1) % f.vertices.size()]]);
  return 0.5 * n.norm();
}

py::dict report_dict(const RadiositySolution& sol) {
  py::dict r;
  r["status"] = std::string(to_string(sol.status));
  r["seconds"] = sol.seconds;
  py::list channels, energy;
  int iterations = 0;
  double residual = 0.0;
  for (int c = 0; c < 3; ++c) {
    const ChannelReport& ch = sol.channels[c];
    py::dict d;
    d["status"] = std::string(to_string(ch.status));
    d["iterations"] = ch.iterations;
    d["matvecs"] = ch.matvecs;
    d["residual"] = ch.residual;
    d["residual_history"] = ch.residual_history;
    d["time_history"] = ch.time_history;
    d["history_iteration"] = ch.history_iteration;
    d["seconds"] = ch.seconds;
    d["note"] = ch.note;
    channels.append(d);
    iterations = std::max(iterations, ch.iterations);
    residual = std::max(residual, ch.residual);
    const EnergyBalance& e = sol.energy[c];
    py::dict b;
    b["emitted"] = e.emitted;
    b["absorbed"] = e.absorbed;
    b["escaped"] = e.escaped;
    b["relative_imbalance"] = e.relative_imbalance;
    b["residual_part"] = e.residual_part;
    b["non_reciprocity_part"] = e.non_reciprocity_part;
    energy.append(b);
  }
  r["iterations"] = iterations;
  r["residual"] = residual;
  r["channels"] = channels;
  r["energy"] = energy;
  return r;
}

// The medium keywords of lambert.solve (the CLI's --medium-box, --sigma-a, ... by the same
// names with underscores), as MediumArgs.
MediumArgs medium_args(const py::dict& d) {
  MediumArgs a;
  const auto doubles = [&](const char* key, size_t n, std::vector<double>& out) {
    if (!d.contains(key) || d[key].is_none()) return;
    out = d[key].cast<std::vector<double>>();
    if (out.size() != n)
      throw UsageError(std::string(key) + " must have " + std::to_string(n) + " components");
    for (double v : out)
      if (!std::isfinite(v)) throw UsageError(std::string(key) + " must be finite");
  };
  doubles("medium_box", 6, a.box);
  doubles("sigma_a", 3, a.sigma_a);
  doubles("sigma_s", 3, a.sigma_s);
  doubles("medium_emission", 3, a.emission);
  if (d.contains("medium_grid") && !d["medium_grid"].is_none())
    a.grid = d["medium_grid"].cast<std::string>();
  if (d.contains("voxels")) a.voxels = d["voxels"].cast<int>();
  if (d.contains("voxel_size")) a.voxel_size = d["voxel_size"].cast<double>();
  if (d.contains("medium_rays")) a.rays = d["medium_rays"].cast<int>();
  if (d.contains("transmittance_samples"))
    a.transmittance_samples = d["transmittance_samples"].cast<int>();
  if (a.voxels < 1 || a.rays < 1 || a.transmittance_samples < 1 || !(a.voxel_size >= 0.0))
    throw UsageError("voxels, medium_rays and transmittance_samples must be >= 1, voxel_size >= 0");
  if (!a.active() && (!a.sigma_a.empty() || !a.sigma_s.empty() || !a.emission.empty()))
    throw UsageError("sigma_a, sigma_s and medium_emission need medium_box (or medium_grid)");
  return a;
}

Shading parse_shading(const std::string& s) {
  if (s == "gouraud") return Shading::Gouraud;
  if (s == "flat") return Shading::Flat;
  throw UsageError("shading must be \"gouraud\" or \"flat\", got \"" + s + "\"");
}

// Releases the GIL for a long call and makes Ctrl-C stop it: Python runs its own SIGINT
// handler only once the GIL is back, so while the call runs SIGINT requests a stop of the
// parallel loops instead (core/parallel.hpp), whose Cancelled becomes KeyboardInterrupt.
// Nested or concurrent calls share one installation (the first installs, the last restores).
class Released {
 public:
  Released() {
    std::lock_guard<std::mutex> lock(mutex());
    if (users()++ == 0) {
      clear_cancel();
      struct sigaction sa {};
      sa.sa_handler = [](int) { request_cancel(); };
      sigemptyset(&sa.sa_mask);
      sigaction(SIGINT, &sa, &previous());
    }
  }
  ~Released() {
    std::lock_guard<std::mutex> lock(mutex());
    if (--users() > 0) return;
    sigaction(SIGINT, &previous(), nullptr);
    // A Ctrl-C that no parallel loop saw (a sequential solver ran) is handed back to Python;
    // one that threw Cancelled is already becoming KeyboardInterrupt.
    if (cancel_requested() && std::uncaught_exceptions() == 0) PyErr_SetInterrupt();
    clear_cancel();
  }
  Released(const Released&) = delete;
  Released& operator=(const Released&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static int& users() {
    static int n = 0;
    return n;
  }
  static struct sigaction& previous() {
    static struct sigaction p {};
    return p;
  }
  py::gil_scoped_release release_;
};

// The keywords given by name (the wrapper sends those not at their declared default), each
// checked by its row of `group` in the declarations (a row of every command: run's cheaper
// --samples is the CLI's only) and handed to `set` as text (choices) or a number.
template <class Set>
void apply_keywords(const py::dict& settings, const std::string& group, const char* function,
                    Set set) {
  for (const auto& [key, value] : settings) {
    const std::string keyword = py::cast<std::string>(key);
    const OptionSpec* row = nullptr;
    for (const OptionSpec& s : option_specs())
      if (s.group == group && s.keyword == keyword && s.commands.empty()) row = &s;
    if (row == nullptr)
      throw UsageError(std::string(function) + ": unknown keyword '" + keyword + "'");
    std::string text;
    double x = 0.0;
    if (row->kind == OptionKind::Choice) {
      text = py::cast<std::string>(value);
      check_option_choice(*row, text, keyword);
    } else {
      x = py::cast<double>(value);
      check_option_value(*row, x, keyword);
    }
    set(row->name, text, x);
  }
}

// Refuses (UsageError, naming the keyword and its reader) the first keyword of `group` given
// that `selection` does not read: the CLI's refusal (unread_options), in Python's names.
void refuse_unread_keywords(const py::dict& settings, const std::string& group,
                            const Selection& selection, const std::string& choice) {
  const OptionGiven given = [&](const std::string& name) {
    const OptionSpec* row = find_option_spec(name, selection.command);  // (none: not a keyword)
    return row && !row->keyword.empty() && row->group == group &&
           settings.contains(row->keyword.c_str());
  };
  const std::vector<std::string> unread = unread_options(given, selection);
  if (unread.empty()) return;
  const OptionSpec& row = option_spec(unread.front(), selection.command);
  throw UsageError(row.keyword + " does not apply to " + choice + " (read by " + row.reader + ")");
}

// The form-factor keywords, set as the CLI sets its options (FormFactorArgs).
FormFactorArgs ff_args_from_keywords(const py::dict& settings) {
  FormFactorArgs args;
  apply_keywords(settings, "form factors", "form_factors",
                 [&](const std::string& name, const std::string& text, double x) {
                   const int n = static_cast<int>(x);  // Integer rows: whole, in int's range
                   if (find_estimator_param(name) != nullptr) {
                     args.set_param(name, x);  // an estimator's (the registry declares it)
                   } else if (name == "--estimator") {
                     args.estimator = text;
                   } else if (name == "--reciprocity") {
                     args.reciprocity = text;
                     args.reciprocity_given = true;
                   } else if (name == "--threshold") {
                     args.threshold = x;
                   } else if (name == "--specular-depth") {
                     args.specular_depth = n;
                     args.specular_given = true;
                   } else if (name == "--specular-rays") {
                     args.specular_rays = n;
                     args.specular_given = true;
                   } else {
                     LAMBERT_CHECK(false, "form_factors: no binding for " + name);
                   }
                 });
  refuse_unread_keywords(settings, "form factors",
                         {"formfactors", "matrix", args.estimator, {}, "", false, false},
                         "estimator " + args.estimator);
  return args;
}

// The solver keywords (SolveOptions); what the solver does not read is refused as `lambert
// solve` refuses it.
SolveOptions solve_options_from_keywords(const py::dict& settings) {
  SolveOptions o;
  apply_keywords(settings, "solver", "solve",
                 [&](const std::string& name, const std::string& text, double x) {
                   if (name == "--solver")
                     o.solver = text;
                   else if (name == "--preconditioner")
                     o.preconditioner = text;
                   else if (name == "--tol")
                     o.tol = x;
                   else if (name == "--max-iter")
                     o.max_iterations = static_cast<int>(x);
                   else if (name == "--omega")
                     o.omega = x;
                   else if (name == "--restart")
                     o.restart = static_cast<int>(x);
                   else
                     LAMBERT_CHECK(false, "solve: no binding for " + name);
                 });
  refuse_unread_keywords(settings, "solver", {"solve", "matrix", "", {o.solver}, "", false, false},
                         "solver " + o.solver);
  return o;
}

// A message of the shared checks with the CLI's option names written as the Python keywords
// ("--samples does not apply" -> "samples does not apply").
std::string with_keywords(std::string message) {
  std::vector<const OptionSpec*> rows;
  for (const OptionSpec& s : option_specs())
    if (!s.keyword.empty() && s.commands.empty()) rows.push_back(&s);
  std::sort(rows.begin(), rows.end(), [](const OptionSpec* a, const OptionSpec* b) {
    return a->name.size() > b->name.size();  // --ff-tol before --ff
  });
  for (const OptionSpec* s : rows)
    for (std::size_t at; (at = message.find(s->name)) != std::string::npos;)
      message.replace(at, s->name.size(), s->keyword);
  return message;
}

// The declarations as Python dicts (lambert.option_specs(): docstrings and references).
py::list option_spec_list() {
  py::list out;
  for (const OptionSpec& spec : option_specs()) {
    py::dict d;
    d["name"] = spec.name;
    d["keyword"] = spec.keyword;
    d["kind"] = spec.kind == OptionKind::Integer ? "integer"
                : spec.kind == OptionKind::Real  ? "real"
                : spec.kind == OptionKind::Flag  ? "flag"
                : spec.kind == OptionKind::Text  ? "text"
                                                 : "choice";
    d["commands"] = spec.commands;
    d["group"] = spec.group;
    d["read_by"] = reader_text(spec);
    d["accepts"] = accepted_text(spec);
    d["default"] = spec.default_text;
    d["doc"] = spec.doc;
    d["choices"] = spec.choices;
    if (spec.kind == OptionKind::Integer || spec.kind == OptionKind::Real)
      d["range"] = py::make_tuple(spec.lo, spec.hi);
    // The estimators that declare it, for an estimator's parameter (form_factors' docstring).
    const DeclaredEstimatorParam* param =
        spec.commands.empty() ? find_estimator_param(spec.name) : nullptr;
    d["estimators"] = param ? param->estimators : std::vector<std::string>{};
    out.append(d);
  }
  return out;
}

}  // namespace
}  // namespace lambert

using namespace lambert;

PYBIND11_MODULE(_lambert, m) {
  m.doc() = "lambert's compiled core; use the `lambert` package.";
  m.attr("__version__") = LAMBERT_VERSION;                 // project(VERSION) in CMakeLists.txt
  m.attr("default_surface_floor") = kDefaultSurfaceFloor;  // geometry/mesh/mesh.hpp
  m.attr("default_hierarchical_epsilon") = HierarchicalOptions{}.epsilon;
  set_log_level(LogLevel::Normal);

  // Never destroyed: the translator may run until the interpreter's last call.
  static PyObject* error = PyErr_NewException("lambert.Error", nullptr, nullptr);
  static PyObject* input_error = PyErr_NewException("lambert.InputError", error, nullptr);
  static PyObject* usage_error = PyErr_NewException(
      "lambert.UsageError", py::make_tuple(py::handle(error), py::handle(PyExc_ValueError)).ptr(),
      nullptr);
  m.attr("Error") = py::handle(error);
  m.attr("InputError") = py::handle(input_error);
  m.attr("UsageError") = py::handle(usage_error);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Cancelled&) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
    } catch (const UsageError& e) {
      PyErr_SetString(usage_error, e.what());
    } catch (const SceneError& e) {
      PyErr_SetString(input_error, e.what());
    } catch (const IoError& e) {
      PyErr_SetString(input_error, e.what());
    } catch (const Error& e) {
      PyErr_SetString(error, e.what());
    } catch (const InternalError& e) {
      PyErr_SetString(PyExc_RuntimeError,
                      (std::string("lambert internal error: ") + e.what()).c_str());
    }
  });

  m.def("set_verbosity", [](int level) {
    if (level < 0 || level > 2) throw UsageError("verbosity is 0 (quiet), 1 or 2");
    set_log_level(static_cast<LogLevel>(level));
  });
  m.def("estimators", &form_factor_estimator_choices);
  m.def("option_specs", &option_spec_list);
  m.def("solvers", &solver_names);
  m.def("builtin_cornell_box_path", &builtin_cornell_box_path);

  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene")
      .def_readonly("source", &Scene::source)
      .def_property_readonly("surfaces",
                             [](const Scene& s) {
                               std::vector<std::string> names;
                               for (const auto& x : s.surfaces) names.push_back(x.name);
                               return names;
                             })
      .def_property_readonly("surface_materials",
                             [](const Scene& s) {
                               std::vector<std::string> names;
                               for (const auto& x : s.surfaces)
                                 names.push_back(s.materials[x.material].name);
                               return names;
                             })
      .def_property_readonly(
          "materials",
          [](const Scene& s) {
            py::list out;
            for (const auto& mat : s.materials) {
              py::dict d;
              d["name"] = mat.name;
              d["rho"] = std::vector<double>{mat.rho.x(), mat.rho.y(), mat.rho.z()};
              d["emission"] =
                  std::vector<double>{mat.emission.x(), mat.emission.y(), mat.emission.z()};
              d["specular"] = mat.specular.any();
              out.append(d);
            }
            return out;
          })
      .def_property_readonly("areas",
                             [](const Scene& s) {
                               std::vector<double> a(s.surfaces.size(), 0.0);
                               for (const Face& f : s.faces) a[f.surface] += face_area(s, f);
                               return a;
                             })
      .def_property_readonly("total_area", &Scene::total_area)
      .def_property_readonly("faces", [](const Scene& s) { return s.faces.size(); })
      .def_property_readonly("bounds",
                             [](const Scene& s) {
                               const auto [lo, hi] = s.bounds();
                               return py::make_tuple(std::vector<double>{lo.x(), lo.y(), lo.z()},
                                                     std::vector<double>{hi.x(), hi.y(), hi.z()});
                             })
      .def("__repr__", [](const Scene& s) {
        return "<lambert.Scene " + s.source + ": " + std::to_string(s.surfaces.size()) +
               " surfaces, " + std::to_string(s.faces.size()) + " faces>";
      });

  m.def(
      "load_scene",
      [](const std::string& path, bool strict,
         std::vector<std::pair<std::string, std::vector<double>>> emit) {
        LoadOptions o;
        o.strict = strict;
        for (const auto& [pattern, e] : emit) o.emit.push_back({pattern, vec3(e, "an emit value")});
        Released release;
        return std::make_shared<Scene>(load_scene_path(path, nullptr, o));
      },
      py::arg("path"), py::arg("strict") = false,
      py::arg("emit") = std::vector<std::pair<std::string, std::vector<double>>>{});

  py::class_<MeshHandle, std::shared_ptr<MeshHandle>> mesh_class(m, "Mesh");
  mesh_class.def_property_readonly("size", [](const MeshHandle& h) { return h.mesh.size(); })
      .def("__len__", [](const MeshHandle& h) { return h.mesh.size(); })
      .def_property_readonly("max_edge", [](const MeshHandle& h) { return h.mesh.max_edge; })
      .def_property_readonly("hash", [](const MeshHandle& h) { return mesh_hash(h.mesh); })
      .def_property_readonly("surface_names",
                             [](const MeshHandle& h) { return h.mesh.surface_names; })
      .def_property_readonly("vertices",
                             [](py::object self) {
                               const auto& mesh = self.cast<const MeshHandle&>().mesh;
                               return view(
                                   mesh.vertices.empty() ? nullptr : mesh.vertices[0].data(),
                                   static_cast<py::ssize_t>(mesh.vertices.size()), 3,
                                   sizeof(Eigen::Vector3d), self);
                             })
      .def_property_readonly("patch_corners",
                             [](const MeshHandle& h) {  // copy: -1 pads triangles
                               std::vector<std::int32_t> v;
                               v.reserve(4 * h.mesh.patches.size());
                               for (const Patch& p : h.mesh.patches)
                                 for (int k = 0; k < 4; ++k)
                                   v.push_back(k < p.vertex_count ? p.vertices[k] : -1);
                               return adopt(std::move(v), {h.mesh.size(), 4});
                             })
      .def_property_readonly("scene",
                             [](const MeshHandle& h) { return std::make_shared<Scene>(h.scene); });

  // Per-patch views: strided over the Patch structs (zero-copy, read-only).
  const auto patch_view = [](auto member, py::ssize_t cols) {
    return [member, cols](py::object self) {
      const PatchMesh& mesh = self.cast<const MeshHandle&>().mesh;
      static const Patch probe;
      using T = std::remove_cv_t<std::remove_reference_t<decltype(probe.*member)>>;
      const py::ssize_t n = mesh.size();
      if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
        const double* first = n ? (mesh.patches[0].*member).data() : nullptr;
        return view(first, n, cols, sizeof(Patch), self);
      } else {
        const T* first = n ? &(mesh.patches[0].*member) : nullptr;
        return view(first, n, 0, sizeof(Patch), self);
      }
    };
  };
  mesh_class.def_property_readonly("areas", patch_view(&Patch::area, 0))
      .def_property_readonly("normals", patch_view(&Patch::normal, 3))
      .def_property_readonly("centroids", patch_view(&Patch::centroid, 3))
      .def_property_readonly("rho", patch_view(&Patch::rho, 3))
      .def_property_readonly("emission", patch_view(&Patch::emission, 3))
      .def_property_readonly("surface_ids", patch_view(&Patch::surface, 0))
      .def_property_readonly("vertex_counts", patch_view(&Patch::vertex_count, 0));

  m.def(
      "mesh_scene",
      [](const Scene& scene, double max_edge, std::int64_t patches, bool discontinuity,
         int surface_floor) {
        if (!(max_edge >= 0.0) || !std::isfinite(max_edge))
          throw UsageError("max_edge must be a finite number >= 0");
        if (patches < 0) throw UsageError("patches must be >= 0");
        if (surface_floor < 0) throw UsageError("surface_floor must be >= 0");
        auto h = std::make_shared<MeshHandle>();
        h->loaded.scene = scene;
        Released release;
        MeshOptions mo;
        mo.max_edge = max_edge;
        mo.target_patches = patches;
        mo.discontinuity = discontinuity;
        mo.surface_floor = surface_floor;
        // As the CLI's load_scene: the planned edge bound, so the mesh is the CLI's.
        const MeshPlan plan = plan_mesh(h->scene, mo);
        if (!mo.discontinuity) mo.max_edge = plan.max_edge;
        h->loaded.mesh = mesh_scene(h->scene, mo);
        h->loaded.max_edge = h->mesh.max_edge;
        h->loaded.discontinuity = mo.discontinuity;
        return h;
      },
      py::arg("scene"), py::arg("max_edge"), py::arg("patches"), py::arg("discontinuity"),
      py::arg("surface_floor"));

  m.def(
      "form_factors",
      [](const MeshHandle& h, const py::dict& settings, std::uint64_t seed, int threads,
         bool with_stderr) {
        if (threads < 0) throw UsageError("threads must be >= 0 (0 = all cores)");
        // As `lambert formfactors`: what the estimator does not read is refused (the rows'
        // `reads`, then auto's pick for this mesh), then the CLI's FormFactorOptions.
        const FormFactorArgs args = ff_args_from_keywords(settings);
        RunArgs run;
        run.seed = seed;
        run.threads = threads;
        run.quiet = true;
        FormFactorOptions o;
        try {
          check_ff_args_for_mesh(args, h.mesh);
          o = make_ff_options(args, run);
        } catch (const UsageError& e) {
          throw UsageError(with_keywords(e.what()));
        }
        o.run.with_stderr = with_stderr;
        FormFactors ff;
        {
          Released release;
          ff = compute_form_factors(h.mesh, o, &h.get_bvh());
        }
        return ff_result(std::move(ff), h);
      },
      py::arg("mesh"), py::arg("settings"), py::arg("seed"), py::arg("threads"), py::arg("stderr"));

  m.def(
      "save_form_factors",
      [](const std::string& path, const MeshHandle& h, const IndexArray& indptr,
         const IndexArray& indices, const ValueArray& data, std::optional<py::tuple> err,
         const std::string& settings, const std::string& precision) {
        if (precision != "double" && precision != "float")
          throw UsageError("precision must be \"double\" or \"float\"");
        FormFactors ff;
        ff.F = csr_from_arrays(h.mesh.size(), indptr, indices, data, "F");
        if (err)
          ff.stderr_F =
              csr_from_arrays(h.mesh.size(), (*err)[2].cast<IndexArray>(),
                              (*err)[1].cast<IndexArray>(), (*err)[0].cast<ValueArray>(), "stderr");
        const ValuePrecision p =
            precision == "float" ? ValuePrecision::Float : ValuePrecision::Double;
        const FormFactorFileInfo info{mesh_hash(h.mesh), settings};
        Released release;
        const std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
        if (ext == ".mtx") {
          if (ff.stderr_F.size() > 0)
            throw UsageError(path + ": standard errors are saved in the binary format only (.bin)");
          write_matrix_market(path, ff.F, info, p);
        } else {
          write_ff_binary(path, ff, info, p);
        }
      },
      py::arg("path"), py::arg("mesh"), py::arg("indptr"), py::arg("indices"), py::arg("data"),
      py::arg("stderr"), py::arg("settings"), py::arg("precision"));

  m.def(
      "load_form_factors",
      [](const std::string& path, const MeshHandle& h) {
        FormFactors ff;
        FormFactorFileInfo info;
        {
          Released release;
          ff = read_form_factors(path, mesh_hash(h.mesh), h.mesh.size(), &info);
        }
        py::dict out = ff_result(std::move(ff), h);
        out["settings"] = info.settings;
        return out;
      },
      py::arg("path"), py::arg("mesh"));

  m.def(
      "solve",
      [](const MeshHandle& h, const IndexArray& indptr, const IndexArray& indices,
         const ValueArray& data, const py::dict& settings, int threads,
         std::optional<ValueArray> initial, const py::dict& medium_options,
         std::optional<std::vector<double>> sky, std::optional<std::vector<double>> sun) {
        SolveOptions o = solve_options_from_keywords(settings);
        const SparseRowMatrix F = csr_from_arrays(h.mesh.size(), indptr, indices, data, "F");
        o.threads = threads;
        if (initial) o.initial_guess = matrix_n3(*initial, h.mesh.size(), "initial_guess");
        const MediumArgs margs = medium_args(medium_options);
        const Daylight light = daylight_from(sky, sun);
        if (light.any() && h.mesh.has_specular())
          throw UsageError("sky and sun do not follow light through mirrors and glass yet");
        if (margs.active()) {  // the extended solve of pipeline/medium_stage, as `lambert solve`
          if (initial) throw UsageError("initial_guess does not combine with a medium");
          if (light.any()) throw UsageError("sky and sun do not combine with a medium");
          const std::shared_ptr<const Medium> medium = make_medium(margs);
          check_medium_scene(h.mesh, nullptr);
          RunArgs run;
          run.threads = threads;
          run.seed =
              medium_options.contains("seed") ? py::cast<std::uint64_t>(medium_options["seed"]) : 1;
          run.quiet = true;
          FormFactors surface;
          surface.F = F;
          RadiosityResult r;
          MediumResult mr;
          {
            Released release;
            h.get_bvh();
            mr = solve_scene_with_medium(h.loaded, surface, medium, margs, o, run, r);
          }
          py::dict report = report_dict(r.solution);
          report["medium"] = py::module_::import("json").attr("loads")(json_text(medium_json(mr)));
          return py::make_tuple(adopt_matrix(r.B), report);
        }
        RadiositySolution sol;
        DaylightSources sources;
        {
          Released release;
          RadiosityProblem problem = make_problem(h.mesh, F);
          // Daylight as `lambert solve --sky/--sun` (the sun's shadow rays with seed 1).
          sources = daylight_sources(light, h.mesh, h.get_bvh(), F, Eigen::VectorXd(), 1, threads);
          if (light.any()) problem.emission += sources.reflected(h.mesh);
          validate_problem(problem);
          sol = solve_radiosity(problem, o);
        }
        py::dict report = report_dict(sol);
        if (light.any())
          report["daylight"] =
              py::module_::import("json").attr("loads")(json_text(daylight_json(light, sources)));
        return py::make_tuple(adopt_matrix(sol.B), report);
      },
      py::arg("mesh"), py::arg("indptr"), py::arg("indices"), py::arg("data"), py::arg("settings"),
      py::arg("threads"), py::arg("initial_guess"), py::arg("medium"), py::arg("sky"),
      py::arg("sun"));

  m.def(
      "heat",
      [](const MeshHandle& h, const IndexArray& indptr, const IndexArray& indices,
         const ValueArray& data, const std::string& surfaces_json, double ambient,
         const std::string& unit, const py::dict& settings, int threads, bool conductors) {
        SolveOptions o = solve_options_from_keywords(settings);
        if (!(ambient >= 0.0) || !std::isfinite(ambient))
          throw UsageError("ambient_temperature must be finite and >= 0 K");
        const double metres = metres_per_unit(unit);
        // The same path as `lambert heat`: conditions resolved per surface, the problem on
        // the patches, the floating-enclosure refusal, then the solve.
        const std::vector<SurfaceCondition> cond = resolve_surface_conditions(
            parse_surface_conditions(surfaces_json, "surfaces"), h.mesh.surface_names);
        FormFactors ff;
        ff.F = csr_from_arrays(h.mesh.size(), indptr, indices, data, "F");
        const ThermalProblem problem = make_heat_problem(h.mesh, cond, ff.F, metres, ambient);
        refuse_floating_enclosure(h.mesh, problem, ff, "surfaces");
        o.threads = threads;
        ThermalSolution sol;
        {
          Released release;
          sol = solve_thermal(problem, o);
        }
        std::vector<std::int32_t> surface_of(h.mesh.size());
        for (std::int32_t i = 0; i < h.mesh.size(); ++i) surface_of[i] = h.mesh.patches[i].surface;
        const auto per_surface = surface_heat(
            sol, problem.area, surface_of, static_cast<std::int32_t>(h.mesh.surface_names.size()));
        const auto vec = [](const Eigen::VectorXd& v) {
          return adopt(std::vector<double>(v.data(), v.data() + v.size()), {v.size()});
        };
        py::list surfaces;
        for (size_t k = 0; k < per_surface.size(); ++k) {
          const SurfaceHeat& sh = per_surface[k];
          py::dict d;
          d["name"] = h.mesh.surface_names[k];
          d["area"] = sh.area;
          d["patches"] = sh.patches;
          d["T"] = sh.T;
          d["T_min"] = sh.T_min;
          d["T_max"] = sh.T_max;
          d["J"] = sh.J;
          d["q"] = sh.q;
          d["Q"] = sh.Q;
          surfaces.append(d);
        }
        py::dict out = report_dict(sol.radiosity);
        out["T"] = vec(sol.T);
        out["J"] = vec(sol.J);
        out["H"] = vec(sol.H);
        out["q"] = vec(sol.q);
        out["Q"] = vec(sol.Q);
        out["area_m2"] = vec(problem.area);
        out["surfaces"] = surfaces;
        out["environment_power"] = sol.environment_power;
        out["closure"] = sol.closure;
        out["max_flux_mismatch"] = sol.max_flux_mismatch;
        out["undefined_temperatures"] = sol.undefined_temperatures;
        if (conductors) {  // as `lambert heat --conductors` (solvers/gebhart.hpp)
          RadiativeConductors c;
          {
            Released release;
            c = radiative_conductors(problem, surface_of,
                                     static_cast<std::int32_t>(h.mesh.surface_names.size()), o);
          }
          py::dict d;
          d["surfaces"] = h.mesh.surface_names;
          d["GR_m2"] = adopt_dense(c.GR);
          d["environment_m2"] = vec(c.environment);
          d["emittance_m2"] = vec(c.emittance);
          d["status"] = to_string(c.status);
          d["residual"] = c.residual;
          out["conductors"] = d;
        }
        return out;
      },
      py::arg("mesh"), py::arg("indptr"), py::arg("indices"), py::arg("data"),
      py::arg("surfaces_json"), py::arg("ambient_temperature"), py::arg("length_unit"),
      py::arg("settings"), py::arg("threads"), py::arg("conductors"));

  m.def(
      "solve_hierarchical",
      [](const Scene& scene, double epsilon, double min_area, int link_rays, double tol,
         int max_iterations, int max_passes, std::uint64_t seed, int threads) {
        if (!(epsilon > 0.0 && epsilon < 1.0)) throw UsageError("epsilon must be in (0, 1)");
        if (!(min_area >= 0.0) || !std::isfinite(min_area))
          throw UsageError("min_area must be >= 0");
        if (!(tol > 0.0 && tol < 1.0)) throw UsageError("tol must be in (0, 1)");
        if (link_rays < 1 || max_iterations < 1 || max_passes < 1 || threads < 0)
          throw UsageError("link_rays, max_iterations and max_passes must be >= 1, threads >= 0");
        HierarchicalOptions o;
        o.epsilon = epsilon;
        o.min_area = min_area;
        o.link_rays = link_rays;
        o.tol = tol;
        o.max_iterations = max_iterations;
        o.max_passes = max_passes;
        o.seed = seed;
        o.threads = threads;
        auto h = std::make_shared<MeshHandle>();
        HierarchicalRun run;
        {
          Released release;
          run = solve_scene_hierarchical(scene, o);
          h->loaded = std::move(run.loaded);
        }
        const py::object loads = py::module_::import("json").attr("loads");
        py::dict report = loads(json_text(hierarchical_json(run)));
        py::list energy;
        for (const HierarchicalEnergy& e : run.stats.energy)
          energy.append(loads(json_text(hierarchical_energy_json(e))));
        report["energy"] = energy;
        std::vector<double> bound(run.error_bound.data(),
                                  run.error_bound.data() + run.error_bound.size());
        report["error_bound"] =
            adopt(std::move(bound), {static_cast<py::ssize_t>(run.error_bound.size())});
        return py::make_tuple(h, adopt_matrix(run.B), report);
      },
      py::arg("scene"), py::arg("epsilon"), py::arg("min_area"), py::arg("link_rays"),
      py::arg("tol"), py::arg("max_iterations"), py::arg("max_passes"), py::arg("seed"),
      py::arg("threads"));

  py::class_<VertexField, std::shared_ptr<VertexField>>(m, "VertexField")
      .def("__len__", &VertexField::size)
      .def_property_readonly("positions",
                             [](py::object self) {
                               const auto& f = self.cast<const VertexField&>();
                               return view(f.positions.empty() ? nullptr : f.positions[0].data(),
                                           f.size(), 3, sizeof(Eigen::Vector3d), self);
                             })
      .def_property_readonly("normals",
                             [](py::object self) {
                               const auto& f = self.cast<const VertexField&>();
                               return view(f.normals.empty() ? nullptr : f.normals[0].data(),
                                           f.size(), 3, sizeof(Eigen::Vector3d), self);
                             })
      .def_property_readonly("surface_ids",
                             [](py::object self) {
                               const auto& f = self.cast<const VertexField&>();
                               return view(f.surface.data(), f.size(), 0, sizeof(std::int32_t),
                                           self);
                             })
      .def_property_readonly("patch_corners",
                             [](py::object self) {
                               const auto& f = self.cast<const VertexField&>();
                               return view(
                                   f.patch_corners.empty() ? nullptr : f.patch_corners[0].data(),
                                   static_cast<py::ssize_t>(f.patch_corners.size()), 4,
                                   4 * sizeof(std::int32_t), self);
                             })
      .def_property_readonly("values", [](const VertexField& f) { return adopt_matrix(f.values); });

  m.def(
      "vertex_radiosity",
      [](const MeshHandle& h, const ValueArray& B, const std::string& mode) {
        const Eigen::MatrixX3d b = matrix_n3(B, h.mesh.size(), "B");
        const VertexInterpolation im = parse_vertex_interpolation(mode);
        Released release;
        return std::make_shared<VertexField>(interpolate_to_vertices(h.mesh, b, im));
      },
      py::arg("mesh"), py::arg("B"), py::arg("mode"));

  m.def(
      "write_vertex_exr",
      [](const std::string& path, const MeshHandle& h, const VertexField& field,
         const std::string& settings) {
        ExrInfo info;
        info.units = "radiosity B (units of the scene's emission E)";
        info.settings = settings;
        info.surface_names = h.mesh.surface_names;
        Released release;
        write_vertex_exr(path, field, info);
      },
      py::arg("path"), py::arg("mesh"), py::arg("field"), py::arg("settings"));

  m.def(
      "write_viewer",
      [](const MeshHandle& h, const ValueArray& B, std::optional<IndexArray> indptr,
         std::optional<IndexArray> indices, std::optional<ValueArray> data,
         const py::dict& settings, int threads, std::optional<std::vector<double>> sky,
         std::optional<std::vector<double>> sun, std::optional<double> ev,
         const std::string& glb_path, const std::string& page_path, const std::string& title) {
        const Eigen::MatrixX3d b = matrix_n3(B, h.mesh.size(), "B");
        const Daylight light = daylight_from(sky, sun);
        SolveOptions o = solve_options_from_keywords(settings);
        o.threads = threads;
        const Camera cam = default_camera(h.scene);
        std::vector<EmitterBasis> bases;
        double linearity = 0.0, exposure = 0.0;
        {
          Released release;
          ShadedField shaded;
          shaded.interpolation = "conservative";
          shaded.field =
              interpolate_to_vertices(h.mesh, b, VertexInterpolation::Conservative, &shaded.power);
          if (indptr) {
            const SparseRowMatrix F = csr_from_arrays(h.mesh.size(), *indptr, *indices, *data, "F");
            RadiosityProblem problem = make_problem(h.mesh, F);
            const DaylightSources sources =
                daylight_sources(light, h.mesh, h.get_bvh(), F, Eigen::VectorXd(), 1, threads);
            if (light.any()) problem.emission += sources.reflected(h.mesh);
            validate_problem(problem);
            bases = emitter_sources(h.mesh, sources);
            solve_emitter_bases(problem, b, o, bases);
          }
          if (ev) {
            exposure = *ev;
          } else {  // automatic, as the CLI's: from a small render of the scene's surfaces
            Camera small = cam;
            const double scale = 128.0 / std::max(cam.width, cam.height);
            small.width = std::max(1, static_cast<int>(cam.width * scale));
            small.height = std::max(1, static_cast<int>(cam.height * scale));
            RenderSettings rs;
            rs.threads = threads;
            rs.progress = false;
            exposure = auto_exposure(render(h.mesh, h.get_bvh(), small, b, shaded.field, rs));
          }
          const std::string why =
              indptr ? ""
                     : "no form factors were given: write_glb(..., F=F) splits the solution "
                       "by light source";
          const GlbContent glb =
              viewer_glb({h.mesh, light, h.scene.source, b, shaded, bases, why, cam, exposure, ""},
                         &linearity);
          write_viewer(glb, glb_path, page_path, title);
        }
        py::dict out;
        out["glb"] = glb_path;
        out["page"] = page_path;
        py::list names;
        for (const EmitterBasis& basis : bases) names.append(basis.name);
        out["light_sources"] = names;
        out["exposure_ev"] = exposure;
        if (!bases.empty()) out["linearity_error"] = linearity;
        return out;
      },
      py::arg("mesh"), py::arg("B"), py::arg("indptr"), py::arg("indices"), py::arg("data"),
      py::arg("settings"), py::arg("threads"), py::arg("sky"), py::arg("sun"), py::arg("ev"),
      py::arg("glb"), py::arg("page"), py::arg("title"));

  m.def(
      "render",
      [](const MeshHandle& h, const ValueArray& B, std::optional<std::vector<double>> eye,
         std::optional<std::vector<double>> look_at, std::optional<std::vector<double>> up,
         std::optional<double> fov, std::optional<int> width, std::optional<int> height,
         const std::string& shading, int antialias, std::uint64_t seed, int threads,
         const std::string& exr, const std::string& png, std::optional<double> ev,
         std::optional<std::vector<double>> sky, std::optional<std::vector<double>> sun,
         std::optional<IndexArray> indptr, std::optional<IndexArray> indices,
         std::optional<ValueArray> data, std::optional<int> direct_rays) {
        Eigen::MatrixX3d b = matrix_n3(B, h.mesh.size(), "B");
        const Daylight light = daylight_from(sky, sun);
        Camera cam = default_camera(h.scene);
        if (eye) cam.eye = vec3(*eye, "eye");
        if (look_at) cam.look_at = vec3(*look_at, "look_at");
        if (up) cam.up = vec3(*up, "up");
        if (fov) {
          if (!(*fov >= 0.1 && *fov <= 179.0))
            throw UsageError("fov must be in [0.1, 179] degrees");
          cam.vfov_degrees = *fov;
        }
        if (width) cam.width = *width;
        if (height) cam.height = *height;
        if (cam.width < 1 || cam.height < 1 || cam.width > 16384 || cam.height > 16384)
          throw UsageError("width and height must be in [1, 16384]");
        if (const std::string why = camera_problem(cam); !why.empty())
          throw UsageError("camera: " + why);
        if (antialias < 1 || antialias > 16) throw UsageError("antialias must be in [1, 16]");
        RenderSettings rs;
        rs.shading = parse_shading(shading);
        rs.antialias = antialias;
        rs.seed = seed;
        rs.threads = threads;
        rs.progress = false;
        if (light.any()) {
          if (rs.shading == Shading::Raytrace)
            throw UsageError("sky and sun are drawn with gouraud or flat shading only");
          rs.daylight = &light;
        }
        // The emitters' direct light per pixel (docs/rendering.md) needs the F that B was
        // solved with: F is read for nothing else, so what cannot draw it refuses F.
        const int rays = direct_rays ? *direct_rays : (indptr ? kDefaultDirectRays : 0);
        if (rays < 0 || rays > 1024) throw UsageError("direct_rays must be in [0, 1024]");
        if (direct_rays && *direct_rays > 0 && !indptr)
          throw UsageError("direct_rays needs F, the form factors B was solved with");
        if (indptr && rs.shading != Shading::Gouraud)
          throw UsageError(
              "F is read for the direct light per pixel, which gouraud shading draws "
              "only (got shading='" +
              shading + "')");
        if (indptr && rays == 0)
          throw UsageError(
              "F is read for the direct light per pixel, and direct_rays=0 turns it "
              "off: leave F out");
        std::unique_ptr<PixelDirectLight> pixel;
        if (indptr) {
          if (light.any() || h.mesh.has_specular())
            throw UsageError(std::string("F is read for the direct light per pixel, which is not "
                                         "drawn ") +
                             (light.any() ? "under sky or sun (the sun is drawn per pixel already)"
                                          : "in a scene with mirrors or glass"));
          pixel = std::make_unique<PixelDirectLight>(h.scene, rays, ff::kRayOffset * h.mesh.scale);
          if (!pixel->usable())
            throw UsageError("the direct light per pixel cannot be drawn: " + pixel->why());
          rs.pixel_direct = pixel.get();
        }
        Image img;
        {
          Released release;
          if (light.has_sun()) {  // drawn per pixel: B without the patches' sun part (seed 1)
            DaylightSources sources;
            sources.sun = sun_patch_irradiance(h.mesh, h.get_bvh(), light, 1, threads);
            b -= sources.reflected_sun(h.mesh);
          }
          VertexField field;
          if (pixel) {
            const SparseRowMatrix F = csr_from_arrays(h.mesh.size(), *indptr, *indices, *data, "F");
            field = emitted_and_indirect_field(h.mesh, indirect_irradiance(h.mesh, F, b),
                                               VertexInterpolation::Conservative);
          } else {
            field = interpolate_to_vertices(h.mesh, b);
          }
          img = render(h.mesh, h.get_bvh(), cam, b, field, rs);
          if (!exr.empty()) {
            ExrInfo info;
            info.units = "radiance B/pi (W m^-2 sr^-1 in the scene's units)";
            write_image_exr(exr, img, info);
          }
          if (!png.empty())
            write_png_preview(png, img, ev ? *ev : auto_exposure(img, light.has_sky()));
        }
        const int w = img.width, hh = img.height;
        return adopt(std::move(img.rgb), {hh, w, 3});
      },
      py::arg("mesh"), py::arg("B"), py::arg("eye"), py::arg("look_at"), py::arg("up"),
      py::arg("fov"), py::arg("width"), py::arg("height"), py::arg("shading"), py::arg("antialias"),
      py::arg("seed"), py::arg("threads"), py::arg("exr"), py::arg("png"), py::arg("ev"),
      py::arg("sky"), py::arg("sun"), py::arg("indptr"), py::arg("indices"), py::arg("data"),
      py::arg("direct_rays"));
}
