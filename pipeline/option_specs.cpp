#include "pipeline/option_specs.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <sstream>

#include "core/error.hpp"
#include "core/memory.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/hierarchical/hierarchical.hpp"
#include "pipeline/adapt_stage.hpp"
#include "pipeline/ff_stage.hpp"
#include "pipeline/heat_problem.hpp"
#include "pipeline/job.hpp"
#include "pipeline/medium_stage.hpp"
#include "pipeline/method.hpp"
#include "pipeline/render_stages.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string join(const std::vector<std::string>& items, const char* sep = ", ") {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : sep) + s;
  return out;
}

template <class T>
std::string list_text(const std::vector<T>& values) {
  std::vector<std::string> items;
  for (const T& v : values) {
    std::ostringstream s;
    s << v;
    items.push_back(s.str());
  }
  return join(items, ",");
}

// ---- When an option is read (the predicates of the rows' `reads`) ----

bool is_one_of(const std::string& value, std::initializer_list<const char*> names) {
  return std::any_of(names.begin(), names.end(), [&](const char* n) { return value == n; });
}

// Some solver that runs is one of `names`.
bool runs_solver(const Selection& s, std::initializer_list<const char*> names) {
  return std::any_of(s.solvers.begin(), s.solvers.end(),
                     [&](const std::string& solver) { return is_one_of(solver, names); });
}

// F is computed (not loaded, not replaced by hierarchical links or a given B).
bool computes_f(const Selection& s) { return !s.estimator.empty(); }

// "--estimator E" may read an option of the estimators `names`: E is one of them, or auto
// and one of them is among auto's picks (hybrid, gather, analytic, by the patch count once
// the scene is meshed: that pick is checked then, ff_stage.cpp).
bool estimator_may_be(const Selection& s, const std::vector<std::string>& names) {
  if (!computes_f(s)) return false;
  if (s.estimator == "auto")
    return std::any_of(names.begin(), names.end(), [](const std::string& n) {
      return is_one_of(n, {"hybrid", "gather", "analytic"});
    });
  return std::find(names.begin(), names.end(), s.estimator) != names.end();
}

// --reciprocity and --symmetrize: the estimators whose F is not reciprocal by construction
// (mc, hybrid and analytic compute each pair once; gather averages by default).
bool averages_pairs(const Selection& s) { return estimator_may_be(s, {"gather", "hemicube"}); }

// --max-iter and --tol: an iterative solver or the hierarchical method runs (direct
// factorises: no iterations, a residual at rounding level whatever the tolerance). The --tol
// of formfactors is --ff-tol's alias: its row is --ff-tol's.
bool iterates(const Selection& s) {
  return s.method == "hierarchical" ||
         std::any_of(s.solvers.begin(), s.solvers.end(),
                     [](const std::string& v) { return v != "direct"; });
}

// Random numbers: the Monte Carlo estimators (auto picks hybrid or gather unless --ff-tol
// makes it analytic), the hemicube's turn about each normal, hierarchical's link rays, a
// medium's exchange, the pixel jitter of --antialias and the camera paths of --shading
// raytrace. analytic is deterministic.
bool draws_random_numbers(const Selection& s) {
  return s.method == "hierarchical" || s.medium || s.random_pixels ||
         (computes_f(s) && s.estimator != "analytic");
}

// ---- The value checks of Text rows ----

std::string rgb_error(const std::string& text) {
  Eigen::Vector3d c;
  return parse_rgb(text, true, c);
}

std::string emit_error(const std::string& text) {
  EmitRule r;
  return parse_emit(text, r);
}

std::string sun_error(const std::string& text) {
  Daylight light;
  return parse_sun(text, light);
}

// Daylight is a first-bounce source of the matrix solve: read where B is solved here by the
// solvers of one machine and drawn by Gouraud or flat shading (the view pass's rays and the
// medium's zones do not meet the sky and the sun yet).
const char* const kDaylightReader =
    "--method matrix solved here on one machine, with Gouraud or flat shading and no medium";
bool reads_daylight(const Selection& s) {
  return s.method == "matrix" && !s.solvers.empty() && s.solvers.front() != "petsc" &&
         s.shading != "raytrace" && !s.medium;
}

std::string size_error(const std::string& text) {
  return parse_size(text) ? "" : "'" + text + "' is not a size such as 512M or 8G";
}

std::string seed_error(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  (void)std::strtoull(text.c_str(), &end, 10);
  const bool ok = !text.empty() && text[0] >= '0' && text[0] <= '9' && *end == '\0' && errno == 0;
  return ok ? "" : "'" + text + "' is not an integer in [0, 2^64 - 1]";
}

std::string exposure_error(const std::string& text) {
  if (text == "auto") return "";
  double v = 0;
  return parse_finite_number(text, v) && std::abs(v) <= 64
             ? ""
             : "'" + text + "' is not 'auto' or a number of stops in [-64, 64]";
}

// ---- Rows ----

// A row under construction: the kind's constructor, then what applies.
struct Row {
  OptionSpec s;
  Row& on(std::vector<std::string> commands) {
    s.commands = std::move(commands);
    return *this;
  }
  Row& py(std::string keyword) {
    s.keyword = std::move(keyword);
    return *this;
  }
  Row& values(int count, char delimiter = 0) {
    s.count = count;
    s.delimiter = delimiter;
    return *this;
  }
  Row& by_method(std::string method, bool solver = false) {
    s.method = std::move(method);
    s.method_solver = solver;
    return *this;
  }
  Row& read_by(std::string reader, std::function<bool(const Selection&)> reads) {
    s.reader = std::move(reader);
    s.reads = std::move(reads);
    return *this;
  }
  Row& fallback(std::string default_text) {
    s.default_text = std::move(default_text);
    return *this;
  }
  Row& described(std::string doc) {
    s.doc = std::move(doc);
    return *this;
  }
};

Row make_row(std::string name, OptionKind kind, std::string doc) {
  Row r;
  r.s.name = std::move(name);
  r.s.kind = kind;
  r.s.doc = std::move(doc);
  return r;
}

Row flag(std::string name, std::string doc) {
  return make_row(std::move(name), OptionKind::Flag, std::move(doc));
}

// Integers up to 2^53 are exact in the double range.
Row integer(std::string name, double lo, double hi, std::string default_text, std::string doc) {
  Row r = make_row(std::move(name), OptionKind::Integer, std::move(doc));
  r.s.lo = lo;
  r.s.hi = hi;
  r.s.default_text = std::move(default_text);
  return r;
}

Row real(std::string name, double lo, double hi, std::string default_text, std::string doc,
         bool open_lo = false, bool open_hi = false) {
  Row r = make_row(std::move(name), OptionKind::Real, std::move(doc));
  r.s.lo = lo;
  r.s.hi = hi;
  r.s.open_lo = open_lo;
  r.s.open_hi = open_hi;
  r.s.default_text = std::move(default_text);
  return r;
}

Row choice(std::string name, std::vector<std::string> choices, std::string default_text,
           std::string doc) {
  Row r = make_row(std::move(name), OptionKind::Choice, std::move(doc));
  r.s.choices = std::move(choices);
  r.s.default_text = std::move(default_text);
  return r;
}

Row text(std::string name, std::string value_name,
         std::function<std::string(const std::string&)> check, std::string default_text,
         std::string doc) {
  Row r = make_row(std::move(name), OptionKind::Text, std::move(doc));
  r.s.value_name = std::move(value_name);
  r.s.check = std::move(check);
  r.s.default_text = std::move(default_text);
  return r;
}

// The commands that compute or load F (--ff).
const std::vector<std::string> kComputesF = {"render", "run", "solve", "compare", "heat"};

std::vector<OptionSpec> make_specs() {
  const FormFactorArgs ff;
  const SolveOptions so;
  const HierarchicalOptions hierarchical;
  const HierarchicalArgs method_args;
  const MediumArgs medium;
  const ShadeArgs shade;
  std::vector<OptionSpec> t;
  std::string group;
  const auto add_row = [&](const Row& r) {
    t.push_back(r.s);
    t.back().group = group;
  };

  group = "scene";
  add_row(flag("--strict",
               "Refuse missing or undefined materials and Kd = 1 instead of defaulting with a "
               "warning"));
  add_row(text("--default-reflectance", "R,G,B", rgb_error, "0.5,0.5,0.5",
               "Reflectance R,G,B of the default material"));
  add_row(real("--max-reflectance", 0.0, 1.0, "",
               "Clamp every Kd channel above R to R, with a warning", true));
  add_row(flag("--vertex-colors-as-reflectance",
               "Each face whose corners all have colours (v x y z r g b) reflects their mean "
               "instead of its material's Kd"));
  add_row(real("--split-angle", 0.0, 180.0, "",
               "Split each surface into NAME/face_1, NAME/face_2, ... at the edges where the "
               "faces' normals turn by more than this many degrees (an STL body into its base "
               "and fins; default: off)"));
  add_row(text("--emit", "NAME_OR_GLOB=R,G,B", emit_error, "",
               "Surfaces (or materials) matching the name or glob emit radiosity R,G,B "
               "(repeatable; later rules win)")
              .values(0));
  add_row(real("--sky", 0.0, kInf, "",
               "A uniform sky of radiance R,G,B (W m^-2 sr^-1) on every direction that escapes "
               "the scene (docs/scenes.md, Daylight)")
              .values(3, ',')
              .on({"run", "solve", "render", "compare"})
              .read_by(kDaylightReader, reads_daylight));
  add_row(text("--sun", "DX,DY,DZ,R,G,B", sun_error, "",
               "A sun: light travelling along DX,DY,DZ with irradiance R,G,B (W/m^2) on a "
               "surface facing it, exact shadows (docs/scenes.md, Daylight)")
              .on({"run", "solve", "render", "compare"})
              .read_by(kDaylightReader, reads_daylight));
  add_row(real("--max-edge", 0.0, kInf, "", "Longest patch edge, in scene units", true)
              .by_method("matrix"));
  add_row(
      integer("--patches", 1, 1e8, "", "Approximate total number of patches").by_method("matrix"));
  add_row(integer("--surface-floor", 0, 1000000, std::to_string(kDefaultSurfaceFloor),
                  "Under a patch target (the default meshing or --patches), every surface gets "
                  "at least N patches, the floors taking at most a quarter of the target "
                  "(largest surfaces first); 0 or 1: none")
              .by_method("matrix"));
  add_row(flag("--discontinuity",
               "Discontinuity meshing: constrained Delaunay triangles whose edges follow the "
               "contact lines of blockers (D0) and the penumbra and umbra boundaries (D1/D2) of "
               "the emitters")
              .by_method("matrix"));
  add_row(integer("--discontinuity-sources", 0, 1000, "0",
                  "With --discontinuity, also trace the shadows of the N non-emitting surfaces "
                  "that reflect the most direct light")
              .by_method("matrix"));

  group = "run";
  add_row(integer("--threads", 1, 1024, "", "Worker threads (default: all cores)"));
  add_row(text("--seed", "UINT", seed_error, "1", "Random seed (results are bitwise reproducible)")
              .read_by("the estimators but analytic, --method hierarchical, a medium, "
                       "--antialias above 1 and --shading raytrace",
                       draws_random_numbers));
  add_row(flag("--quiet", "No progress or log output on stderr"));
  add_row(flag("--verbose", "More log output on stderr"));
  add_row(text("--max-memory", "SIZE", size_error, "",
               "Refuse a job whose estimated memory exceeds SIZE (e.g. 512M, 8G; 0 = no check; "
               "default: $LAMBERT_MAX_MEMORY, else the available memory)"));

  group = "form factors";
  add_row(choice("--estimator", form_factor_estimator_choices(), ff.estimator,
                 "Form-factor estimator (auto: hybrid below " + std::to_string(kAutoGatherPatches) +
                     " patches, gather from there)")
              .py("estimator")
              .by_method("matrix"));
  // The estimators' parameters, from the registry's declarations (EstimatorParam): read by
  // the estimators that declare them. run's --samples has a cheaper default.
  for (const DeclaredEstimatorParam& d : estimator_params()) {
    const EstimatorParam& p = d.param;
    Row r = p.integer
                ? integer(p.option, p.lo, p.hi, std::to_string(std::lround(p.fallback)), p.doc)
                : real(p.option, p.lo, p.hi, number_text(p.fallback), p.doc, p.open_lo);
    r.by_method("matrix").read_by(
        estimator_readers_text(d.estimators),
        [readers = d.estimators](const Selection& s) { return estimator_may_be(s, readers); });
    add_row(Row(r).py(p.keyword));
    if (p.option == "--samples")
      add_row(r.on({"run"})
                  .fallback(std::to_string(kRunDefaultSamples))
                  .described(p.doc + "; run's default is cheaper than the other commands'"));
  }
  add_row(
      real("--threshold", 0.0, 1.0, number_text(ff.threshold), "Drop form factors below this value")
          .py("threshold")
          .by_method("matrix")
          .read_by("a computed F", computes_f));
  add_row(choice("--reciprocity", {"auto", "none", "average"}, ff.reciprocity,
                 "Replace A_i F_ij and A_j F_ji by their mean: none, average, or auto (average "
                 "for gather, none for the others)")
              .py("reciprocity")
              .by_method("matrix")
              .read_by("the estimators gather and hemicube", averages_pairs));
  add_row(flag("--symmetrize", "Alias of --reciprocity average")
              .by_method("matrix")
              .read_by("the estimators gather and hemicube", averages_pairs));
  add_row(
      integer("--specular-depth", 0, 64, std::to_string(ff.specular_depth),
              "Specular bounces a ray follows through mirrors and glass (extended form "
              "factors, ray-traced shading); 0 = specular surfaces only receive and block")
          .py("specular_depth")
          .read_by("a computed F (extended form factors) and --shading raytrace (camera "
                   "paths)",
                   [](const Selection& s) { return computes_f(s) || s.shading == "raytrace"; }));
  add_row(integer("--specular-rays", 1, 1 << 24, std::to_string(ff.specular_rays),
                  "Rays per patch that trace the specular paths of the extended form factors "
                  "(scenes with mirrors or glass)")
              .py("specular_rays")
              .read_by("a computed F (the extended form factors through mirrors and glass)",
                       computes_f));
  add_row(text("--ff", "FILE", nullptr, "",
               "Use a saved form-factor file (from `formfactors -o`) and the settings stored in "
               "it; excludes the form-factor options")
              .on(kComputesF)
              .by_method("matrix"));

  group = "solver";
  add_row(choice("--solver", solver_names(), so.solver, "Solver (see `lambert solvers`)")
              .py("solver")
              .by_method("matrix", true));
  std::ostringstream tol_doc, iter_doc;
  tol_doc << "Stop when ||E - K B||_2 / ||E||_2 <= tol (--method hierarchical: when the largest "
             "change of a leaf's B over the largest B <= tol; its default "
          << hierarchical.tol << ")";
  iter_doc << "Iteration limit per channel (--method hierarchical: sweeps per refinement pass; "
              "its default "
           << hierarchical.max_iterations << ")";
  add_row(real("--tol", 1e-16, 0.5, number_text(so.tol), tol_doc.str())
              .py("tol")
              .read_by("the iterative solvers and --method hierarchical", iterates));
  add_row(integer("--max-iter", 1, 1e8, std::to_string(so.max_iterations), iter_doc.str())
              .py("max_iterations")
              .read_by("the iterative solvers and --method hierarchical", iterates));
  add_row(
      real("--omega", 1e-3, 1.999, number_text(so.omega), "SOR relaxation factor, in (0, 2)")
          .py("omega")
          .by_method("matrix", true)
          .read_by("the solver sor", [](const Selection& s) { return runs_solver(s, {"sor"}); }));
  add_row(choice("--preconditioner", {"none", "diagonal", "ilut"}, so.preconditioner,
                 "bicgstab/gmres/cg preconditioner")
              .py("preconditioner")
              .by_method("matrix", true)
              .read_by("the solvers bicgstab, gmres and cg", [](const Selection& s) {
                return runs_solver(s, {"bicgstab", "gmres", "cg"});
              }));
  add_row(
      integer("--restart", 1, 10000, std::to_string(so.restart), "GMRES restart length")
          .py("restart")
          .by_method("matrix", true)
          .read_by("the solver gmres (and --distributed's PETSc GMRES)", [](const Selection& s) {
            return runs_solver(s, {"gmres", "petsc"});
          }));
  add_row(flag("--ambient", "southwell: add the ambient term (display estimate)")
              .by_method("matrix", true)
              .read_by("the solver southwell",
                       [](const Selection& s) { return runs_solver(s, {"southwell"}); }));
  add_row(choice("--solvers", solver_names(), "", "Comma-separated solvers (default: all)")
              .values(0, ',')
              .on({"compare"})
              .by_method("matrix", true));
  add_row(text("--radiosity", "FILE", nullptr, "",
               "Per-patch radiosity CSV from `lambert solve` (instead of computing F and "
               "solving)")
              .on({"render"})
              .by_method("matrix", true));

  group = "method";
  add_row(choice("--method", method_names(), "matrix",
                 "How B is computed: matrix (F + solver) or hierarchical (adaptive links with "
                 "clustering, no F)"));
  const std::string epsilon_doc =
      "hierarchical: refine a link while its power error exceeds EPSILON x the emitted power";
  // (0, 1): epsilon is a fraction of the emitted power; at 1 no link would ever refine.
  add_row(real("--epsilon", 0.0, 1.0, number_text(method_args.epsilon), epsilon_doc, true, true)
              .by_method("hierarchical"));
  add_row(real("--epsilon", 0.0, 1.0, list_text(method_args.epsilons),
               epsilon_doc + " (comma-separated: one hierarchical run each)", true, true)
              .values(0, ',')
              .on({"compare"})
              .by_method("hierarchical"));
  add_row(real("--min-area", 0.0, kInf, number_text(method_args.min_area),
               "hierarchical: smallest element area, scene units^2 (0 = total area x 1e-5)")
              .by_method("hierarchical"));
  add_row(integer("--link-rays", 1, 1024, std::to_string(method_args.link_rays),
                  "hierarchical: visibility rays per element link (samples per cluster link)")
              .by_method("hierarchical"));

  group = "adaptive meshing";
  add_row(integer("--adapt", 1, 1000, "",
                  "Adaptive meshing: ROUNDS rounds of solve, estimate each patch's error, bisect "
                  "the worst 20 % (conforming longest-edge bisection), update their form "
                  "factors, re-solve from the previous solution")
              .by_method("matrix"));
  add_row(integer("--adapt-patches", 1, 1e8, "",
                  "Adaptive meshing until the mesh has about N patches (with --adapt: whichever "
                  "comes first)")
              .by_method("matrix"));

  group = "medium";
  add_row(real("--medium-box", -kInf, kInf, "",
               "Participating medium: homogeneous box X0,Y0,Z0,X1,Y1,Z1 (scene units)")
              .values(6, ',')
              .by_method("matrix"));
  add_row(real("--sigma-a", 0.0, kInf, "", "Medium absorption R,G,B (1/scene unit)")
              .values(3, ',')
              .by_method("matrix"));
  add_row(real("--sigma-s", 0.0, kInf, "",
               "Medium scattering R,G,B (1/scene unit, isotropic; sigma-a + sigma-s grey)")
              .values(3, ',')
              .by_method("matrix"));
  add_row(real("--medium-emission", 0.0, kInf, "",
               "Medium emitted power per volume R,G,B (W/scene unit^3)")
              .values(3, ',')
              .by_method("matrix"));
  add_row(text("--medium-grid", "FILE", input_file_error, "",
               "Heterogeneous medium from a grid file (docs/media.md: bounds, resolution, "
               "voxels)")
              .by_method("matrix"));
  add_row(integer("--voxels", 1, 256, std::to_string(medium.voxels),
                  "Medium zones along the box's longest axis (others in proportion)")
              .by_method("matrix"));
  add_row(real("--voxel-size", 0.0, kInf, "", "Medium zone edge (scene units) instead of --voxels",
               true)
              .by_method("matrix"));
  add_row(integer("--medium-rays", 1, 1 << 20, std::to_string(medium.rays),
                  "Medium: rays per patch and per zone")
              .by_method("matrix"));
  add_row(integer("--transmittance-samples", 1, 1 << 16,
                  std::to_string(medium.transmittance_samples),
                  "Medium: point pairs per patch pair for the surface-to-surface transmittance")
              .by_method("matrix"));

  group = "camera";
  add_row(real("--eye", -kInf, kInf, "", "Camera position X Y Z (default: the scene's camera)")
              .values(3));
  add_row(real("--look-at", -kInf, kInf, "", "Point the camera looks at, X Y Z").values(3));
  add_row(real("--up", -kInf, kInf, "", "Camera up vector X Y Z").values(3));
  add_row(real("--fov", 0.1, 179.0, "", "Vertical field of view, degrees"));
  add_row(text("--size", "WxH", nullptr, "", "Image size WxH in pixels (default 512x512)"));
  add_row(choice("--view", {"front", "three-quarter", "top"}, "",
                 "Frame the whole scene from the front (level), a three-quarter view (35 deg "
                 "round, 30 deg above) or straight above, about its up axis (y; z for STL), "
                 "instead of its camera; --eye, --look-at, --up and --fov still apply"));

  group = "shading";
  add_row(choice("--shading", {"gouraud", "flat", "raytrace"}, "",
                 "gouraud (B/pi interpolated from the vertices), flat (per patch) or raytrace "
                 "(camera rays followed through mirrors and glass up to --specular-depth "
                 "bounces, Gouraud or --final-gather at diffuse hits); default gouraud"));
  add_row(flag("--flat", "Per-patch (flat) shading: the same as --shading flat"));
  add_row(integer("--final-gather", 1, 65536, "",
                  "N: at diffuse hits, exact direct light plus N cosine rays reading the "
                  "solution's indirect light (implies --shading raytrace)"));
  add_row(
      flag("--wireframe", "Draw the patch edges (black, about one pixel wide) over the shading"));
  add_row(integer("--antialias", 1, 16, std::to_string(shade.antialias),
                  "K: K x K stratified samples per pixel"));
  add_row(text("--exposure", "EV|auto", exposure_error, shade.exposure,
               "PNG/PLY exposure in stops (pixel x 2^EV), or auto (key value 0.36)"));
  add_row(choice("--vertex-interp", {"auto", "conservative", "area", "linear", "exact-direct"},
                 shade.vertex_interp,
                 "Per-vertex reconstruction: conservative (area-weighted, rescaled per surface "
                 "to conserve power), area (area-weighted only), linear (local linear fit of "
                 "the patches around the vertex, rescaled like conservative), exact-direct "
                 "(exact direct light at each vertex plus the area-weighted indirect light), "
                 "or auto (exact-direct on a --discontinuity mesh, linear on an --adapt mesh, "
                 "else conservative)"));
  add_row(integer("--direct-rays", 0, 1024, "",
                  "N: the emitters' direct light drawn per pixel with N shadow rays per pixel "
                  "sample (crisp shadows; exact where a light is all seen or all hidden) over "
                  "the vertex field of the rest; 0 = all from the vertices; default 8 where it "
                  "applies (not over an exact-direct field, nor with mirrors or glass, --sky or "
                  "--sun, or more than 64 emitting faces)")
              .read_by("Gouraud shading of a B solved over F (not --radiosity, a medium or "
                       "--method hierarchical)",
                       [](const Selection& s) {
                         return s.shading == "gouraud" && !s.medium && !s.solvers.empty();
                       }));

  group = "distributed";
  const std::string distributed_doc =
      "Run as one rank of an MPI job (mpirun -np K lambert ...; the mpi build, "
      "docs/cluster.md): F's rows split over the ranks";
  add_row(flag("--distributed", distributed_doc).on({"formfactors"}));
  add_row(flag("--distributed", distributed_doc + ", solved with PETSc").on({"run", "solve"}));
  add_row(text("--petsc-options", "TEXT", nullptr, "",
               "With --distributed: PETSc options for the solve, e.g. \"-ksp_type bcgs "
               "-pc_type jacobi\" (default GMRES with Jacobi)")
              .on({"run", "solve"}));

  group = "outputs";
  add_row(
      text("--output", "DIR", nullptr, "out", "Output directory (created if needed)").on({"run"}));
  add_row(text("--name", "TEXT", nullptr, "",
               "File name prefix (default: the scene file's stem; cornell for the built-in box)")
              .on({"run"}));
  add_row(text("--output", "FILE", output_file_error, "radiosity.csv",
               "Per-patch radiosity CSV (patch,surface,area,R,G,B); the summary goes to the "
               "same name with .json (none beside a device such as /dev/null)")
              .on({"solve"}));
  add_row(text("--output", "FILE", output_file_error, "render.exr",
               "Rendered linear HDR image (OpenEXR)")
              .on({"render"}));
  add_row(text("--png", "FILE", output_file_error, "",
               "Tone-mapped sRGB preview (default: --output with .png)")
              .on({"render"}));
  add_row(
      text("--vertex-exr", "FILE", output_file_error, "", "Also write the per-vertex radiosity EXR")
          .on({"render"}));
  add_row(text("--ply", "FILE", output_file_error, "", "Also write the coloured patch mesh as PLY")
              .on({"render"}));
  add_row(text("--glb", "FILE", nullptr, "",
               "Also write the solution as glTF 2.0 (render: one colour set per light source; "
               "heat: temperature and flux per vertex) and the viewer page (FILE with .html; "
               "docs/viewer.md)")
              .on({"render", "heat"}));
  add_row(text("--output", "FILE", output_file_error, "",
               "Output: F.mtx (Matrix Market), F.bin (binary), or JSON with --by-surface/--point")
              .on({"formfactors"}));
  add_row(text("--report", "FILE", output_file_error, "",
               "Diagnostics JSON (default: OUTPUT with .report.json)")
              .on({"formfactors"}));
  add_row(flag("--stderr", "Also estimate and save per-entry standard errors (binary format)")
              .on({"formfactors"}));
  add_row(choice("--ff-precision", {"double", "float"}, "double",
                 "Saved values: double (exact) or float (half the value bytes, relative "
                 "rounding <= 6e-8)")
              .on({"formfactors"}));
  add_row(flag("--by-surface", "Write the surface-to-surface view-factor table as JSON")
              .on({"formfactors"}));
  add_row(real("--point", -kInf, kInf, "", "Sensor point X,Y,Z (differential area)")
              .values(3, ',')
              .on({"formfactors"}));
  add_row(real("--normal", -kInf, kInf, "", "Sensor normal NX,NY,NZ")
              .values(3, ',')
              .on({"formfactors"}));
  for (const char* command : {"compare", "accuracy"})
    add_row(text("--output", "DIR/|PREFIX", output_prefix_error, command,
                 "Output directory (existing or ending in /) or file prefix")
                .on({command}));
  add_row(flag("--list-surfaces",
               "Print one line per surface (name, tab, material, tab, emits yes/no) and stop "
               "(the names --emit matches)")
              .on({"info"}));
  add_row(flag("--markdown", "Print the reference table of docs/options.md (Markdown)")
              .on({"options"}));

  group = "heat";
  add_row(text("--surfaces", "FILE", input_file_error, "",
               "JSON file: surface name (or \"*\") -> {\"emissivity\": E, \"temperature\": T} "
               "or {\"emissivity\": E, \"heat_flux\": Q}")
              .on({"heat"}));
  add_row(real("--ambient-temperature", 0.0, kInf, "",
               "Temperature (K) of the black environment that receives what escapes an open "
               "scene (default 0: escaping radiation is lost)")
              .on({"heat"}));
  std::vector<std::string> units;
  for (const auto& [name, metres] : length_units()) units.push_back(name);
  add_row(choice("--length-unit", units, "m", "Unit of the scene's coordinates").on({"heat"}));
  // heat's files may go into the folder its -o DIR/ creates: their folders are checked by
  // the job's plan (check_job_files), which knows it, not when the line is parsed.
  add_row(text("--output", "FILE.csv|FILE.vtu|DIR/|PREFIX", output_prefix_error, "heat",
               "FILE.csv: the per-surface table, its summary FILE.json (none for a device "
               "such as /dev/null); FILE.vtu: per-patch results as VTK cell data, the "
               "per-surface table as field data, FILE.json; PREFIX: PREFIX_surfaces.csv, "
               "PREFIX_patches.csv, PREFIX.json (a folder DIR/ gives DIR/heat_*)")
              .on({"heat"}));
  add_row(text("--patches-csv", "FILE", nullptr, "",
               "Per-patch table (T, J, H, q, Q); with -o PREFIX instead of PREFIX_patches.csv")
              .on({"heat"}));
  add_row(text("--conductors", "FILE", nullptr, "",
               "Radiative conductors GR_ij = e_i A_i B_ij (m^2, Gebhart factors B) per "
               "surface pair, and to the environment, as a CSV matrix (also in the summary)")
              .on({"heat"}));
  add_row(text("--vertex-exr", "FILE", nullptr, "",
               "Per-vertex EXR with channels temperature (K), heat_flux (W/m^2), radiosity")
              .on({"heat"}));
  add_row(text("--ply", "FILE", nullptr, "",
               "PLY mesh coloured by --image-quantity, with temperature, heat_flux, radiosity")
              .on({"heat"}));
  add_row(text("--image", "FILE", nullptr, "", "Colour-mapped rendering (PNG) with a legend")
              .on({"heat"}));
  add_row(choice("--image-quantity", {"temperature", "flux"}, "temperature",
                 "What --image and --ply colour")
              .on({"heat"}));

  group = "accuracy";
  add_row(choice("--case",
                 {"parallel_squares", "perpendicular_squares", "unit_cube", "coaxial_disks",
                  "partial_shadow"},
                 "", "Built-in analytic case instead of SCENE")
              .on({"accuracy"}));
  add_row(choice("--estimators", form_factor_estimators(), "",
                 "Estimator families to run (default: mc, hybrid, hemicube; gather on request)")
              .values(0, ',')
              .on({"accuracy"}));
  add_row(integer("--mc-samples", 1, 1 << 20, "4,16,64", "Sample counts for mc")
              .values(0, ',')
              .on({"accuracy"}));
  add_row(integer("--hybrid-samples", 1, 1 << 20, "4,16,64", "Sample counts for hybrid")
              .values(0, ',')
              .on({"accuracy"}));
  add_row(integer("--gather-rays", 1, 1 << 24, "256,1024,4096", "Rays per patch for gather")
              .values(0, ',')
              .on({"accuracy"}));
  add_row(integer("--hemicube-res", 4, 8192, "32,64,128,256", "Resolutions for hemicube")
              .values(0, ',')
              .on({"accuracy"}));
  add_row(flag("--symmetrize", "Also run each hemicube resolution symmetrized").on({"accuracy"}));
  add_row(integer("--reference-samples", 1, 1 << 20, "1024",
                  "Samples of the hybrid reference (scenes without a closed form)")
              .on({"accuracy"}));
  return t;
}

bool names_command(const OptionSpec& s, const std::string& command) {
  return std::find(s.commands.begin(), s.commands.end(), command) != s.commands.end();
}

}  // namespace

std::string number_text(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

const std::vector<OptionSpec>& option_specs() {
  static const std::vector<OptionSpec> kSpecs = make_specs();
  return kSpecs;
}

const OptionSpec* find_option_spec(const std::string& name, const std::string& command) {
  const OptionSpec* every = nullptr;
  for (const OptionSpec& s : option_specs()) {
    if (s.name != name) continue;
    if (!command.empty() && names_command(s, command)) return &s;
    if (s.commands.empty() && every == nullptr) every = &s;
  }
  return every;
}

const OptionSpec& option_spec(const std::string& name, const std::string& command) {
  const OptionSpec* s = find_option_spec(name, command);
  LAMBERT_CHECK(s != nullptr,
                "no option_specs() row for " + name + (command.empty() ? "" : " of " + command));
  return *s;
}

std::string reader_text(const OptionSpec& spec) {
  if (!spec.reader.empty()) return spec.reader;
  if (!spec.method.empty()) return "--method " + spec.method;
  return "every choice";
}

std::vector<std::string> option_group(const std::string& group) {
  std::vector<std::string> out;
  for (const OptionSpec& s : option_specs())
    if (s.group == group && std::find(out.begin(), out.end(), s.name) == out.end())
      out.push_back(s.name);
  return out;
}

namespace {

std::string one_value_text(const OptionSpec& spec) {
  switch (spec.kind) {
    case OptionKind::Flag:
      return "flag";
    case OptionKind::Integer:
      return "an integer in [" + std::to_string(static_cast<long long>(spec.lo)) + ", " +
             std::to_string(static_cast<long long>(spec.hi)) + "]";
    case OptionKind::Real:
      if (std::isinf(spec.lo) && std::isinf(spec.hi)) return "a finite number";
      if (std::isinf(spec.hi))
        return "a number " + std::string(spec.open_lo ? "> " : ">= ") + number_text(spec.lo);
      return "a number in " + std::string(spec.open_lo ? "(" : "[") + number_text(spec.lo) + ", " +
             number_text(spec.hi) + (spec.open_hi ? ")" : "]");
    case OptionKind::Choice:
      return "one of " + join(spec.choices);
    case OptionKind::Text:
      return spec.value_name;
  }
  return "";
}

}  // namespace

std::string accepted_text(const OptionSpec& spec) {
  const std::string one = one_value_text(spec);
  if (spec.kind == OptionKind::Flag || spec.kind == OptionKind::Text) return one;
  if (spec.count == 0)
    return std::string(spec.delimiter ? "comma-separated, each " : "repeatable, each ") + one;
  if (spec.count > 1)
    return std::to_string(spec.count) + (spec.delimiter ? " comma-separated values" : " values") +
           ", each " + one;
  return one;
}

std::string option_value_error(const OptionSpec& spec, const std::string& text) {
  const std::string refusal = "'" + text + "' is not " + one_value_text(spec);
  switch (spec.kind) {
    case OptionKind::Flag:
      return "";
    case OptionKind::Text:
      return spec.check ? spec.check(text) : "";
    case OptionKind::Choice:
      for (const auto& c : spec.choices)
        if (c == text) return "";
      return refusal;
    case OptionKind::Integer:
    case OptionKind::Real:
      break;
  }
  double x = 0.0;
  if (!parse_finite_number(text, x)) return refusal;
  if (spec.kind == OptionKind::Integer && x != std::floor(x)) return refusal;
  const bool above = spec.open_lo ? x > spec.lo : x >= spec.lo;
  const bool below = spec.open_hi ? x < spec.hi : x <= spec.hi;
  return above && below ? "" : refusal;
}

void check_option_value(const OptionSpec& spec, double value, const std::string& as) {
  const bool above = spec.open_lo ? value > spec.lo : value >= spec.lo;
  const bool below = spec.open_hi ? value < spec.hi : value <= spec.hi;
  if (std::isfinite(value) && above && below &&
      (spec.kind != OptionKind::Integer || value == std::floor(value)))
    return;
  throw UsageError(as + ": " + number_text(value) + " is not " + one_value_text(spec));
}

void check_option_choice(const OptionSpec& spec, const std::string& value, const std::string& as) {
  for (const auto& c : spec.choices)
    if (c == value) return;
  throw UsageError(as + ": '" + value + "' is not " + one_value_text(spec));
}

std::string output_file_error(const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(path).parent_path();
  std::error_code ec;
  if (!dir.empty() && !fs::is_directory(dir, ec))
    return "cannot write '" + path + "': directory '" + dir.string() + "' does not exist";
  return "";
}

std::string output_prefix_error(const std::string& path) {
  if (!path.empty() && path.back() == '/') return "";  // created when writing
  return output_file_error(path);
}

std::string input_file_error(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec) ? "" : "'" + path + "': no such file";
}

}  // namespace lambert
