#include "apps/options.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "core/error.hpp"
#include "core/memory.hpp"
#include "pipeline/option_specs.hpp"

namespace lambert {
namespace {

// The CLI11 check of a declared option (pipeline/option_specs.hpp): its range or choices,
// and what it accepts as the value's name in --help.
CLI::Validator declared_check(const OptionSpec& spec) {
  return CLI::Validator([spec](std::string& text) { return option_value_error(spec, text); },
                        accepted_text(spec));
}

// Registers a declared option under `names` (its first name is the table's), bound to
// `field`, with the table's description, check and default.
template <class T>
CLI::Option* add_declared(CLI::App* cmd, const std::string& names, T& field) {
  const std::string first = names.substr(0, names.find(','));
  const OptionSpec& spec = option_spec(first);
  return cmd->add_option(names, field, spec.doc)
      ->check(declared_check(spec))
      ->capture_default_str();
}

}  // namespace

OptionGiven option_given_on(const CLI::App* cmd) {
  return [cmd](const std::string& name) {
    const CLI::Option* o = cmd->get_option_no_throw(name);
    return o != nullptr && o->count() > 0 && "--" + o->get_lnames().front() == name;
  };
}

CLI::Validator finite_number(double lo, double hi, bool open_low, bool open_high) {
  const std::string range = std::isinf(hi)
                                ? (open_low ? "> " : ">= ") + number_text(lo)
                                : "in " + std::string(open_low ? "(" : "[") + number_text(lo) +
                                      ", " + number_text(hi) + (open_high ? ")" : "]");
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double x = 0;
        const bool ok = parse_finite_number(text, x) && (open_low ? x > lo : x >= lo) &&
                        (open_high ? x < hi : x <= hi);
        return ok ? "" : "'" + text + "' is not a finite number " + range;
      },
      "NUMBER " + range);
}

CLI::Validator any_finite_number() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double x = 0;
        return parse_finite_number(text, x) ? "" : "'" + text + "' is not a finite number";
      },
      "NUMBER");
}

void add_scene_options(CLI::App* cmd, SceneArgs& args) {
  cmd->add_option(
      "scene", args.scene,
      "OBJ or STL scene file, told apart by content (default: the built-in Cornell box)");
  cmd->add_flag(
      "--strict", args.load.strict,
      "Refuse missing or undefined materials and Kd = 1 instead of defaulting with a warning");
  cmd->add_option_function<std::string>(
         "--default-reflectance",
         [&args](const std::string& s) {
           parse_rgb(s, true, args.load.default_reflectance);
           args.default_reflectance_given = true;
         },
         "Reflectance R,G,B of the default material (default 0.5,0.5,0.5)")
      ->check([](const std::string& s) {
        Eigen::Vector3d c;
        return parse_rgb(s, true, c);
      });
  cmd->add_option("--max-reflectance", args.load.max_reflectance,
                  "Clamp every Kd channel above R to R (0 < R <= 1), with a warning")
      ->check([](const std::string& s) {
        double r = 0;
        return parse_finite_number(s, r) && r > 0 && r <= 1
                   ? std::string()
                   : "'" + s + "' is not a number in (0, 1]";
      });
  cmd->add_flag("--vertex-colors-as-reflectance", args.load.vertex_colors_as_reflectance,
                "Each face whose corners all have colours (v x y z r g b) reflects their mean "
                "instead of its material's Kd");
  cmd->add_option("--emit", args.emit,
                  "NAME_OR_GLOB=R,G,B: surfaces (or materials) matching the name or glob emit "
                  "radiosity R,G,B (repeatable; later rules win)")
      ->check([](const std::string& s) {
        EmitRule r;
        return parse_emit(s, r);
      });
  auto* edge = cmd->add_option("--max-edge", args.max_edge, "Longest patch edge, in scene units")
                   ->check(finite_number(0.0, std::numeric_limits<double>::infinity(), true));
  cmd->add_option("--patches", args.patches, "Approximate total number of patches")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{100000000}))
      ->excludes(edge);
  auto* disc = cmd->add_flag(
      "--discontinuity", args.discontinuity,
      "Discontinuity meshing: constrained Delaunay triangles whose edges follow the contact "
      "lines of blockers (D0) and the penumbra and umbra boundaries (D1/D2) of the emitters");
  cmd->add_option("--discontinuity-sources", args.discontinuity_sources,
                  "With --discontinuity, also trace the shadows of the N non-emitting surfaces "
                  "that reflect the most direct light (default 0)")
      ->check(CLI::Range(0, 1000))
      ->needs(disc);
}

void add_run_options(CLI::App* cmd, RunArgs& args) {
  args.given = option_given_on(cmd);
  cmd->add_option("-j,--threads", args.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--seed", args.seed, "Random seed (results are bitwise reproducible)");
  cmd->add_flag("-q,--quiet", args.quiet, "No progress or log output on stderr");
  cmd->add_flag("-v,--verbose", args.verbose, "More log output on stderr");
  cmd->add_option("--max-memory", args.max_memory,
                  "Refuse a job whose estimated memory exceeds SIZE (e.g. 512M, 8G; 0 = no "
                  "check; default: $LAMBERT_MAX_MEMORY, else the available memory)")
      ->check([](const std::string& s) {
        return parse_size(s) ? std::string() : "'" + s + "' is not a size such as 512M or 8G";
      });
}

CLI::Validator output_file_check() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        namespace fs = std::filesystem;
        const fs::path dir = fs::path(path).parent_path();
        std::error_code ec;
        if (!dir.empty() && !fs::is_directory(dir, ec))
          return "cannot write '" + path + "': directory '" + dir.string() + "' does not exist";
        return "";
      },
      "FILE");
}

CLI::Validator output_prefix_check() {
  return CLI::Validator(
      [](std::string& out) -> std::string {
        if (!out.empty() && out.back() == '/') return "";  // created when writing
        return output_file_check()(out);
      },
      "DIR/|PREFIX");
}

void add_method_options(CLI::App* cmd, MethodArgs& args, bool epsilon_list) {
  args.given = option_given_on(cmd);
  cmd->add_option("--method", args.name,
                  "How B is computed: matrix (F + solver) or hierarchical (adaptive links with "
                  "clustering, no F)")
      ->check(CLI::IsMember(method_names()))
      ->capture_default_str();
  // (0, 1): epsilon is a fraction of the emitted power; at 1 no link would ever refine.
  const CLI::Validator epsilon_range = finite_number(0.0, 1.0, true, true);
  const std::string epsilon_help =
      "hierarchical: refine a link while its power error exceeds EPSILON x the emitted power";
  if (epsilon_list)
    cmd->add_option("--epsilon", args.hierarchical.epsilons,
                    epsilon_help + " (comma-separated: one hierarchical run each)")
        ->delimiter(',')
        ->check(epsilon_range)
        ->capture_default_str();
  else
    cmd->add_option("--epsilon", args.hierarchical.epsilon, epsilon_help)
        ->check(epsilon_range)
        ->capture_default_str();
  cmd->add_option("--min-area", args.hierarchical.min_area,
                  "hierarchical: smallest element area, scene units^2 (0 = total area x 1e-5)")
      ->check(finite_number(0.0, std::numeric_limits<double>::infinity()))
      ->capture_default_str();
  cmd->add_option("--link-rays", args.hierarchical.link_rays,
                  "hierarchical: visibility rays per element link (samples per cluster link)")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
}

void add_solve_options(CLI::App* cmd, SolveOptions& o, bool with_solver) {
  if (with_solver) add_declared(cmd, "--solver", o.solver);
  add_declared(cmd, "--tol", o.tol);
  add_declared(cmd, "--max-iter", o.max_iterations);
  add_declared(cmd, "--omega", o.omega);
  add_declared(cmd, "--preconditioner", o.preconditioner);
  add_declared(cmd, "--restart", o.restart);
  cmd->add_flag("--ambient", o.ambient, "southwell: add the ambient term (display estimate)");
}

void add_ff_options(CLI::App* cmd, FormFactorArgs& args, bool with_load, bool tol_alias) {
  std::vector<CLI::Option*> compute_only;
  compute_only.push_back(add_declared(cmd, "--estimator", args.estimator));
  compute_only.push_back(
      add_declared(cmd, "--samples", args.samples)->each([&args](const std::string&) {
        args.samples_given = true;
      }));
  compute_only.push_back(add_declared(cmd, "--rays", args.rays)->each([&args](const std::string&) {
    args.rays_given = true;
  }));
  compute_only.push_back(add_declared(cmd, tol_alias ? "--ff-tol,--tol" : "--ff-tol", args.tol)
                             ->each([&args](const std::string&) { args.tol_given = true; }));
  compute_only.push_back(add_declared(cmd, "--threshold", args.threshold));
  compute_only.push_back(add_declared(cmd, "--hemicube-res", args.hemicube_resolution));
  CLI::Option* reciprocity =
      add_declared(cmd, "--reciprocity", args.reciprocity)->each([&args](const std::string&) {
        args.reciprocity_given = true;
      });
  compute_only.push_back(reciprocity);
  compute_only.push_back(
      cmd->add_flag("--symmetrize", args.symmetrize, "Alias of --reciprocity average")
          ->each([&args](const std::string&) { args.reciprocity_given = true; })
          ->excludes(reciprocity));
  add_declared(cmd, "--specular-depth", args.specular_depth)->each([&args](const std::string&) {
    args.specular_given = true;
  });
  compute_only.push_back(
      add_declared(cmd, "--specular-rays", args.specular_rays)->each([&args](const std::string&) {
        args.specular_given = true;
      }));
  if (!with_load) return;
  CLI::Option* ff = cmd->add_option(
      "--ff", args.ff_file,
      "Use a saved form-factor file (from `formfactors -o`) and the settings stored in it; "
      "excludes the options above");
  // A loaded F keeps the settings that made it: an option that would change them is refused
  // rather than silently ignored (and then misreported).
  for (CLI::Option* o : compute_only) ff->excludes(o);
}

void add_adapt_options(CLI::App* cmd, AdaptArgs& args) {
  cmd->add_option("--adapt", args.rounds,
                  "Adaptive meshing: ROUNDS rounds of solve, estimate each patch's error, bisect "
                  "the worst 20 % (conforming longest-edge bisection), update their form "
                  "factors, re-solve from the previous solution")
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--adapt-patches", args.patches,
                  "Adaptive meshing until the mesh has about N patches (with --adapt: whichever "
                  "comes first)")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{100000000}));
}

void add_medium_options(CLI::App* cmd, MediumArgs& args) {
  args.given = option_given_on(cmd);
  const CLI::Validator non_negative = finite_number(0.0, std::numeric_limits<double>::infinity());
  cmd->add_option("--medium-box", args.box,
                  "Participating medium: homogeneous box X0,Y0,Z0,X1,Y1,Z1 (scene units)")
      ->delimiter(',')
      ->expected(6)
      ->check(any_finite_number());
  cmd->add_option("--sigma-a", args.sigma_a, "Medium absorption R,G,B (1/scene unit)")
      ->delimiter(',')
      ->expected(3)
      ->check(non_negative);
  cmd->add_option("--sigma-s", args.sigma_s,
                  "Medium scattering R,G,B (1/scene unit, isotropic; sigma-a + sigma-s grey)")
      ->delimiter(',')
      ->expected(3)
      ->check(non_negative);
  cmd->add_option("--medium-emission", args.emission,
                  "Medium emitted power per volume R,G,B (W/scene unit^3)")
      ->delimiter(',')
      ->expected(3)
      ->check(non_negative);
  cmd->add_option(
         "--medium-grid", args.grid,
         "Heterogeneous medium from a grid file (docs/media.md: bounds, resolution, voxels)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--voxels", args.voxels,
                  "Medium zones along the box's longest axis (others in proportion)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  cmd->add_option("--voxel-size", args.voxel_size,
                  "Medium zone edge (scene units) instead of --voxels")
      ->check(finite_number(0.0, std::numeric_limits<double>::infinity(), true));
  cmd->add_option("--medium-rays", args.rays, "Medium: rays per patch and per zone")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  cmd->add_option("--transmittance-samples", args.transmittance_samples,
                  "Medium: point pairs per patch pair for the surface-to-surface transmittance")
      ->check(CLI::Range(1, 1 << 16))
      ->capture_default_str();
}

void add_camera_options(CLI::App* cmd, CameraArgs& args) {
  cmd->add_option("--eye", args.eye, "Camera position X Y Z (default: the scene's camera)")
      ->expected(3)
      ->check(any_finite_number());
  cmd->add_option("--look-at", args.look_at, "Point the camera looks at, X Y Z")
      ->expected(3)
      ->check(any_finite_number());
  cmd->add_option("--up", args.up, "Camera up vector X Y Z")
      ->expected(3)
      ->check(any_finite_number());
  cmd->add_option("--fov", args.fov, "Vertical field of view, degrees")
      ->check(finite_number(0.1, 179.0));
  cmd->add_option("--size", args.size, "Image size WxH in pixels (default 512x512)");
}

void add_shade_options(CLI::App* cmd, ShadeArgs& args) {
  cmd->add_option("--shading", args.shading,
                  "gouraud (B/pi interpolated from the vertices), flat (per patch) or raytrace "
                  "(camera rays followed through mirrors and glass up to --specular-depth "
                  "bounces, Gouraud or --final-gather at diffuse hits); default gouraud")
      ->check(CLI::IsMember({"gouraud", "flat", "raytrace"}));
  cmd->add_flag("--flat", args.flat, "Per-patch (flat) shading: the same as --shading flat");
  cmd->add_option("--final-gather", args.final_gather,
                  "N: at diffuse hits, exact direct light plus N cosine rays reading the "
                  "solution's indirect light (implies --shading raytrace)")
      ->check(CLI::Range(1, 65536));
  cmd->add_flag("--wireframe", args.wireframe,
                "Draw the patch edges (black, about one pixel wide) over the shading");
  cmd->add_option("--antialias", args.antialias, "K: K x K stratified samples per pixel")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  cmd->add_option("--exposure", args.exposure,
                  "PNG/PLY exposure in stops (pixel x 2^EV), or auto (key value 0.36)")
      ->check([](const std::string& s) -> std::string {
        if (s == "auto") return "";
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        return !s.empty() && *end == '\0' && std::isfinite(v) && std::abs(v) <= 64
                   ? ""
                   : "must be 'auto' or a number of stops in [-64, 64]";
      })
      ->capture_default_str();
  cmd->add_option("--vertex-interp", args.vertex_interp,
                  "Per-vertex reconstruction: conservative (area-weighted, rescaled per surface "
                  "to conserve power), area (area-weighted only), exact-direct (exact direct "
                  "light at each vertex plus the area-weighted indirect light), or auto "
                  "(exact-direct on a --discontinuity mesh, else conservative)")
      ->check(CLI::IsMember({"auto", "conservative", "area", "exact-direct"}))
      ->capture_default_str();
}

}  // namespace lambert
