#pragma once
// The command line's options: every CLI11 registration and check lives here, bound to the
// pipeline's option structs (pipeline/), which know nothing of CLI11. After parsing, a struct's
// `given` asks CLI11 which options were on the command line (option_given_on).

#include <CLI/CLI.hpp>
#include <string>

#include "pipeline/adapt_stage.hpp"
#include "pipeline/ff_stage.hpp"
#include "pipeline/job.hpp"
#include "pipeline/medium_stage.hpp"
#include "pipeline/method.hpp"
#include "pipeline/render_stages.hpp"
#include "pipeline/solve_stage.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// The OptionGiven of a subcommand (it must outlive the run): true for a long name
/// ("--omega") when the option whose first long name that is was on its command line.
OptionGiven option_given_on(const CLI::App* cmd);

/// Adds the positional SCENE, the loading options (--strict, --default-reflectance,
/// --max-reflectance, --vertex-colors-as-reflectance, --emit), --max-edge / --patches and
/// --discontinuity / --discontinuity-sources to a subcommand.
void add_scene_options(CLI::App* cmd, SceneArgs& args);

/// Adds -j/--threads, --seed, -q/--quiet, -v/--verbose and --max-memory to a subcommand.
void add_run_options(CLI::App* cmd, RunArgs& args);

/// CLI11 check for an output file option: its directory must exist (checked before any
/// work, so a long computation never ends in a failed write).
CLI::Validator output_file_check();

/// CLI11 check for an output prefix option (see output_prefix): a name ending in '/' is a
/// directory to create; otherwise the prefix's directory must exist.
CLI::Validator output_prefix_check();

/// CLI11 check for a floating-point option: a finite number (NaN and inf refused) in
/// [lo, hi], open at lo when `open_low` and at hi when `open_high`; hi = infinity means no
/// upper bound. The message states the range.
CLI::Validator finite_number(double lo, double hi, bool open_low = false, bool open_high = false);

/// CLI11 check for a floating-point value that may be any finite number (NaN, inf refused).
CLI::Validator any_finite_number();

/// Adds --method, --epsilon (a comma-separated list when `epsilon_list`), --min-area and
/// --link-rays to a subcommand.
void add_method_options(CLI::App* cmd, MethodArgs& args, bool epsilon_list = false);

/// Adds --tol, --max-iter, --omega, --preconditioner, --restart, --ambient (and --solver when
/// `with_solver`) bound to `options`.
void add_solve_options(CLI::App* cmd, SolveOptions& options, bool with_solver);

/// Adds the form-factor options to a subcommand. `with_load` adds --ff FILE, which excludes
/// the options that only steer a computation (--estimator, --samples, --rays, --threshold,
/// --hemicube-res, --reciprocity, --symmetrize): given together, they are a usage error.
/// `tol_alias` also names --ff-tol --tol (the formfactors command, which has no solver).
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
