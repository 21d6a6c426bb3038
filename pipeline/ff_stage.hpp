#pragma once
// The form-factor settings of every command that needs F, and the stage that computes F or
// loads a saved one (with its checks and report pieces).

#include <set>
#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "io/json.hpp"
#include "pipeline/job.hpp"

namespace lambert {

struct Medium;

/// `run`'s --samples default: cheaper than the other commands' (the parameter's declared
/// default), for a quick first picture.
constexpr int kRunDefaultSamples = 16;

/// --estimator and the estimators' parameters (estimator_params(): --samples, --rays,
/// --ff-tol, --hemicube-res, and whatever the registry declares), --threshold,
/// --reciprocity, --symmetrize, the specular options, --ff.
struct FormFactorArgs {
  std::string estimator = "auto";
  /// The estimators' parameters by option name ("--samples"); an absent one is at its
  /// declared default. The front ends bind to these values (CLI) or set them (set_param).
  EstimatorParamValues params;
  /// The estimator parameters the user gave (a front end's set_param or `each` marks them).
  std::set<std::string> params_given;
  double threshold = 0.0;
  std::string reciprocity = "auto";
  bool symmetrize = false;  ///< alias of --reciprocity average
  std::string ff_file;      ///< load F from this file instead of computing it
  /// --specular-depth: specular bounces followed by the extended form factors and by the
  /// ray-traced view pass (with --ff it steers the view pass only; F keeps its own).
  int specular_depth = 8;
  int specular_rays = 1024;  ///< --specular-rays: rays per patch of the extended part
  /// --specular-depth or --specular-rays was on the command line.
  bool specular_given = false;
  bool reciprocity_given = false;  ///< --reciprocity or --symmetrize was on the command line

  /// The value of the estimator parameter `option`: as set, else its declared default.
  double param(const std::string& option) const;
  /// Sets the estimator parameter `option` as given by the user.
  void set_param(const std::string& option, double value);
  /// The user gave the estimator parameter `option`.
  bool given(const std::string& option) const { return params_given.count(option) > 0; }
};

/// What reads an estimator parameter, for messages and the option reference: "the estimator
/// gather", "the estimators hybrid and mc" (its DeclaredEstimatorParam::estimators).
std::string estimator_readers_text(const std::vector<std::string>& estimators);

/// Adds F to a job plan: --ff as an input, or the computation's options for the memory
/// estimate.
void plan_form_factors(JobPlan& plan, const FormFactorArgs& args, const RunArgs& run,
                       bool with_stderr = false);

/// The estimator of a selection (pipeline/option_scope.hpp): --estimator, or "" when F is loaded
/// from --ff.
std::string selected_estimator(const FormFactorArgs& args);

/// Refuses (UsageError) an estimator parameter (--samples, --rays, --ff-tol, ...) that the
/// estimator --estimator auto picks for `patches` patches does not read; nothing for a named
/// estimator.
void check_auto_pick(const FormFactorArgs& args, std::int64_t patches);

/// Builds FormFactorOptions from the arguments ("auto" stays unresolved: it needs the patch
/// count). Throws UsageError when a named estimator does not read a parameter that was given
/// (--rays with a pair estimator or the hemicube, --samples with gather).
FormFactorOptions make_ff_options(const FormFactorArgs& args, const RunArgs& run);

/// The checks of the arguments against the meshed scene, before any work: check_auto_pick,
/// and the specular options refused on a mesh without mirror or glass (UsageError).
void check_ff_args_for_mesh(const FormFactorArgs& args, const PatchMesh& mesh);

/// The estimator parameters given that `estimator` (resolved) does not declare, as option
/// names ("--rays", "--samples", "--ff-tol"), in registry order; empty when none.
std::vector<std::string> unused_count_options(const FormFactorArgs& args,
                                              const std::string& estimator);

/// Computes F for the scene, or loads --ff (refusing a file made for another mesh), and
/// logs a one-line summary on stderr. A loaded F's `options` are the settings stored in the
/// file (threads and progress from `run`); when the file records none, `options.estimator`
/// is empty (reports then show the settings as unknown) and a warning is logged. A loaded F
/// holding a participating medium's zones (`options.contents.medium_zones` > 0) needs `medium`
/// (UsageError without one) with the extinction it was computed for (SceneError otherwise).
FormFactors obtain_form_factors(const LoadedScene& scene, const FormFactorArgs& args,
                                const RunArgs& run, bool with_stderr = false,
                                const Medium* medium = nullptr);

/// The share of the exchange Σ_i A_i Σ_j F_ij (patch rows) that the pairs whose visibility
/// could not be sampled as designed carry (FormFactorStats::unverified_exchange): the size of
/// the warning's effect; 0 when F exchanges nothing.
double unverified_exchange_share(const FormFactors& ff, const PatchMesh& mesh);

/// Warns once per cause (analysis.hpp's find_lighting_problems) when F makes the result
/// silently B = E: nothing sees anything, or an emitter sees nothing. (A scene without an
/// emitter is warned about by the loader.)
void warn_about_lighting(const PatchMesh& mesh, const SparseF& F);

/// Refuses (SceneError, exit 1) a scene in which a closed set of lossless surfaces makes
/// I - rho F singular (analysis.hpp's find_closed_lossless), naming them and the channel;
/// with `solving` false (F is only saved) the same message is a warning instead.
void check_closed_lossless(const PatchMesh& mesh, const FormFactors& ff, bool solving = true);

/// The settings that made F, for reports: ff_settings_report (io/ff_settings.hpp: estimator
/// (the resolved one), estimator_requested ("auto" or null), samples, rays_per_patch (--rays),
/// seed, threshold, hemicube_resolution, tol (analytic's --ff-tol, else null), reciprocity,
/// symmetrize (reciprocity == average), extended (F holds specular paths), specular_depth and
/// specular_rays (null unless extended); every setting null when unknown, see
/// obtain_form_factors), then loaded_from ("" when computed here).
Json ff_settings_json(const FormFactorOptions& options, const std::string& loaded_from);

/// What reciprocity averaging changed (FormFactorStats' reciprocity_* members): {applied,
/// max_relative_change, mean_relative_change, rows_scaled, balance_iterations,
/// max_row_sum_before}.
Json reciprocity_json(const FormFactors& ff);

/// The same as one line of key=value text for image and PLY metadata: "[ff=FILE ]" followed
/// by format_ff_settings(), or "settings=unknown".
std::string ff_settings_text(const FormFactorOptions& options, const std::string& loaded_from);

}  // namespace lambert
