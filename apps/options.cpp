#include "apps/options.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "pipeline/option_specs.hpp"

namespace lambert {
namespace {

// "-j,--threads" -> "--threads": the long name a declaration is keyed by.
std::string first_long_name(const std::string& names) {
  for (std::size_t at = 0; at <= names.size();) {
    const std::size_t comma = std::min(names.find(',', at), names.size());
    const std::string name = names.substr(at, comma - at);
    if (name.rfind("--", 0) == 0) return name;
    at = comma + 1;
  }
  LAMBERT_CHECK(false, "no long name in '" + names + "'");
  return "";
}

// The CLI11 check of a declared option: each value against its row, and the row's accepted
// values as the value's name in --help.
CLI::Validator declared_check(const OptionSpec& spec) {
  const OptionSpec* row = &spec;  // the table is static
  return CLI::Validator([row](std::string& text) { return option_value_error(*row, text); },
                        accepted_text(spec));
}

}  // namespace

CLI::Option* apply_declaration(CLI::Option* o, const OptionSpec& spec) {
  if (spec.kind != OptionKind::Flag) {
    o->check(declared_check(spec));
    if (spec.delimiter) o->delimiter(spec.delimiter);
    if (spec.count > 1) o->expected(spec.count);
  }
  if (!spec.default_text.empty()) o->default_str(spec.default_text);
  return o;
}

const OptionSpec& declaration(const CLI::App* cmd, const std::string& names) {
  return option_spec(first_long_name(names), cmd->get_name());
}

OptionGiven option_given_on(const CLI::App* cmd) {
  return [cmd](const std::string& name) {
    const CLI::Option* o = cmd->get_option_no_throw(name);
    return o != nullptr && o->count() > 0 && "--" + o->get_lnames().front() == name;
  };
}

CLI::Option* add_declared_function(CLI::App* cmd, const std::string& names,
                                   std::function<void(const std::string&)> set) {
  const OptionSpec& spec = declaration(cmd, names);
  return apply_declaration(cmd->add_option_function<std::string>(names, std::move(set), spec.doc),
                           spec);
}

void add_scene_options(CLI::App* cmd, SceneArgs& args) {
  cmd->add_option(
      "scene", args.scene,
      "OBJ, STL or PLY scene file, told apart by content (default: the built-in Cornell box)");
  add_declared(cmd, "--strict", args.load.strict);
  add_declared_function(cmd, "--default-reflectance", [&args](const std::string& s) {
    parse_rgb(s, true, args.load.default_reflectance);
    args.default_reflectance_given = true;
  });
  add_declared(cmd, "--max-reflectance", args.load.max_reflectance);
  add_declared(cmd, "--vertex-colors-as-reflectance", args.load.vertex_colors_as_reflectance);
  add_declared(cmd, "--split-angle", args.load.split_angle);
  add_declared(cmd, "--emit", args.emit);
  if (find_option_spec("--sky", cmd->get_name())) {  // the commands that solve for B
    add_declared(cmd, "--sky", args.sky);
    add_declared(cmd, "--sun", args.sun);
  }
  auto* edge = add_declared(cmd, "--max-edge", args.max_edge);
  add_declared(cmd, "--patches", args.patches)->excludes(edge);
  auto* floor = add_declared(cmd, "--surface-floor", args.surface_floor)->excludes(edge);
  auto* disc = add_declared(cmd, "--discontinuity", args.discontinuity);
  floor->excludes(disc);
  add_declared(cmd, "--discontinuity-sources", args.discontinuity_sources)->needs(disc);
}

void add_run_options(CLI::App* cmd, RunArgs& args) {
  args.given = option_given_on(cmd);
  add_declared(cmd, "-j,--threads", args.threads);
  add_declared(cmd, "--seed", args.seed);
  add_declared(cmd, "-q,--quiet", args.quiet);
  add_declared(cmd, "-v,--verbose", args.verbose);
  add_declared(cmd, "--max-memory", args.max_memory);
}

void add_method_options(CLI::App* cmd, MethodArgs& args, bool epsilon_list) {
  args.given = option_given_on(cmd);
  add_declared(cmd, "--method", args.name);
  if (epsilon_list)
    add_declared(cmd, "--epsilon", args.hierarchical.epsilons);
  else
    add_declared(cmd, "--epsilon", args.hierarchical.epsilon);
  add_declared(cmd, "--min-area", args.hierarchical.min_area);
  add_declared(cmd, "--link-rays", args.hierarchical.link_rays);
}

void add_solve_options(CLI::App* cmd, SolveOptions& o, bool with_solver) {
  if (with_solver) add_declared(cmd, "--solver", o.solver);
  add_declared(cmd, "--tol", o.tol);
  add_declared(cmd, "--max-iter", o.max_iterations);
  add_declared(cmd, "--omega", o.omega);
  add_declared(cmd, "--preconditioner", o.preconditioner);
  add_declared(cmd, "--restart", o.restart);
  add_declared(cmd, "--ambient", o.ambient);
}

void add_ff_options(CLI::App* cmd, FormFactorArgs& args, bool with_load, bool tol_alias) {
  std::vector<CLI::Option*> compute_only;
  compute_only.push_back(add_declared(cmd, "--estimator", args.estimator));
  // The estimators' parameters, as the registry declares them (bound to args.params, whose
  // elements stay put; a value set before, such as run's cheaper --samples, is the default).
  for (const DeclaredEstimatorParam& d : estimator_params()) {
    const std::string& option = d.param.option;
    double& value = args.params.emplace(option, args.param(option)).first->second;
    const std::string names =
        tol_alias && !d.param.alias.empty() ? option + "," + d.param.alias : option;
    CLI::Option* o = add_declared(cmd, names, value)->each([&args, option](const std::string&) {
      args.params_given.insert(option);
    });
    if (d.param.integer) o->type_name("INT");  // bound to a double, checked whole by its row
    compute_only.push_back(o);
  }
  compute_only.push_back(add_declared(cmd, "--threshold", args.threshold));
  CLI::Option* reciprocity =
      add_declared(cmd, "--reciprocity", args.reciprocity)->each([&args](const std::string&) {
        args.reciprocity_given = true;
      });
  compute_only.push_back(reciprocity);
  compute_only.push_back(add_declared(cmd, "--symmetrize", args.symmetrize)
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
  CLI::Option* ff = add_declared(cmd, "--ff", args.ff_file);
  // A loaded F keeps the settings that made it: an option that would change them is refused
  // rather than silently ignored (and then misreported).
  for (CLI::Option* o : compute_only) ff->excludes(o);
}

void add_adapt_options(CLI::App* cmd, AdaptArgs& args) {
  add_declared(cmd, "--adapt", args.rounds);
  add_declared(cmd, "--adapt-patches", args.patches);
}

void add_medium_options(CLI::App* cmd, MediumArgs& args) {
  args.given = option_given_on(cmd);
  add_declared(cmd, "--medium-box", args.box);
  add_declared(cmd, "--sigma-a", args.sigma_a);
  add_declared(cmd, "--sigma-s", args.sigma_s);
  add_declared(cmd, "--medium-emission", args.emission);
  add_declared(cmd, "--medium-grid", args.grid);
  add_declared(cmd, "--voxels", args.voxels);
  add_declared(cmd, "--voxel-size", args.voxel_size);
  add_declared(cmd, "--medium-rays", args.rays);
  add_declared(cmd, "--transmittance-samples", args.transmittance_samples);
}

void add_camera_options(CLI::App* cmd, CameraArgs& args) {
  add_declared(cmd, "--eye", args.eye);
  add_declared(cmd, "--look-at", args.look_at);
  add_declared(cmd, "--up", args.up);
  add_declared(cmd, "--fov", args.fov);
  add_declared(cmd, "--size", args.size);
  add_declared(cmd, "--view", args.view);
}

void add_shade_options(CLI::App* cmd, ShadeArgs& args) {
  add_declared(cmd, "--shading", args.shading);
  add_declared(cmd, "--flat", args.flat);
  add_declared(cmd, "--final-gather", args.final_gather);
  add_declared(cmd, "--wireframe", args.wireframe);
  add_declared(cmd, "--antialias", args.antialias);
  add_declared(cmd, "--exposure", args.exposure);
  add_declared(cmd, "--vertex-interp", args.vertex_interp);
  add_declared(cmd, "--direct-rays", args.direct_rays);
}

}  // namespace lambert
