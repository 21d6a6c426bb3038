#pragma once
// The command line's options: every option is registered with add_declared, which binds it to
// a field of the pipeline's option structs (pipeline/, which know nothing of CLI11) and takes
// its description, check, value count and default from its row in pipeline/option_specs.cpp.
// After parsing, a struct's `given` asks CLI11 which options were on the command line
// (option_given_on).

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <type_traits>

#include "pipeline/adapt_stage.hpp"
#include "pipeline/ff_stage.hpp"
#include "pipeline/job.hpp"
#include "pipeline/medium_stage.hpp"
#include "pipeline/method.hpp"
#include "pipeline/option_specs.hpp"
#include "pipeline/render_stages.hpp"
#include "pipeline/solve_stage.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// The declaration (pipeline/option_specs.hpp) of the option `names` ("-j,--threads": keyed
/// by the first long name) on the subcommand `cmd`; a missing row is a bug.
const OptionSpec& declaration(const CLI::App* cmd, const std::string& names);

/// Applies a declaration to a registered option: its check (each value against the row),
/// value count, delimiter and the default --help shows.
CLI::Option* apply_declaration(CLI::Option* o, const OptionSpec& spec);

/// Registers the declared option `names` on `cmd`, bound to `field` (a flag for bool), with
/// the row's description, check and default: every option of every command is registered
/// this way, so the table is the one place an option is described and checked.
template <class T>
CLI::Option* add_declared(CLI::App* cmd, const std::string& names, T& field) {
  const OptionSpec& spec = declaration(cmd, names);
  if constexpr (std::is_same_v<T, bool>)
    return apply_declaration(cmd->add_flag(names, field, spec.doc), spec);
  else
    return apply_declaration(cmd->add_option(names, field, spec.doc), spec);
}

/// add_declared for an option whose value goes through `set`.
CLI::Option* add_declared_function(CLI::App* cmd, const std::string& names,
                                   std::function<void(const std::string&)> set);

/// The OptionGiven of a subcommand (it must outlive the run): true for a long name
/// ("--omega") when the option whose first long name that is was on its command line.
OptionGiven option_given_on(const CLI::App* cmd);

/// Adds the positional SCENE, the loading options (--strict, --default-reflectance,
/// --max-reflectance, --vertex-colors-as-reflectance, --emit), --max-edge / --patches and
/// --discontinuity / --discontinuity-sources to a subcommand.
void add_scene_options(CLI::App* cmd, SceneArgs& args);

/// Adds -j/--threads, --seed, -q/--quiet, -v/--verbose and --max-memory to a subcommand.
void add_run_options(CLI::App* cmd, RunArgs& args);

/// Adds --method, --epsilon (a comma-separated list when `epsilon_list`), --min-area and
/// --link-rays to a subcommand.
void add_method_options(CLI::App* cmd, MethodArgs& args, bool epsilon_list = false);

/// Adds --tol, --max-iter, --omega, --preconditioner, --restart, --ambient (and --solver when
/// `with_solver`) bound to `options`.
void add_solve_options(CLI::App* cmd, SolveOptions& options, bool with_solver);

/// Adds the form-factor options to a subcommand: --estimator, every estimator parameter the
/// registry declares (estimator_params(): --samples, --rays, --ff-tol, --hemicube-res, ...),
/// --threshold, --reciprocity, --symmetrize, the specular options. `with_load` adds --ff
/// FILE, which excludes the options that only steer a computation: given together, they are a
/// usage error. `tol_alias` also registers the parameters' aliases (--ff-tol as --tol: the
/// formfactors command, which has no solver).
void add_ff_options(CLI::App* cmd, FormFactorArgs& args, bool with_load = true,
                    bool tol_alias = false);

/// Adds --adapt and --adapt-patches to a subcommand.
void add_adapt_options(CLI::App* cmd, AdaptArgs& args);

/// Adds the medium options to a subcommand.
void add_medium_options(CLI::App* cmd, MediumArgs& args);

/// Adds the camera options to a subcommand.
void add_camera_options(CLI::App* cmd, CameraArgs& args);

/// Adds the shading options to a subcommand.
void add_shade_options(CLI::App* cmd, ShadeArgs& args);

}  // namespace lambert
