#pragma once
// Form-factor options shared by every command that needs F, and the step that computes F
// or loads a saved one.

#include <CLI/CLI.hpp>
#include <string>

#include "apps/common.hpp"
#include "geometry/formfactors/formfactors.hpp"

namespace lambert {

/// --estimator, --samples, --threshold, --hemicube-res, --symmetrize, --ff.
struct FormFactorArgs {
  std::string estimator = "hybrid";
  int samples = 32;
  double threshold = 0.0;
  int hemicube_resolution = 128;
  bool symmetrize = false;
  std::string ff_file;  ///< load F from this file instead of computing it
};

/// Adds the form-factor options to a subcommand. `with_load` adds --ff FILE.
void add_ff_options(CLI::App* cmd, FormFactorArgs& args, bool with_load = true);

/// Builds FormFactorOptions from the arguments.
FormFactorOptions make_ff_options(const FormFactorArgs& args, const RunArgs& run);

/// Computes F for the scene, or loads --ff (refusing a file made for another mesh), and
/// logs a one-line summary on stderr.
FormFactors obtain_form_factors(const LoadedScene& scene, const FormFactorArgs& args,
                                const RunArgs& run, bool with_stderr = false);

/// Warns once per cause (analysis.hpp's find_lighting_problems) when F makes the result
/// silently B = E: nothing sees anything, or an emitter sees nothing. `solving` adds the
/// no-emitter warning (F by itself needs no emitter).
void warn_about_lighting(const PatchMesh& mesh, const SparseF& F, bool solving);

}  // namespace lambert
