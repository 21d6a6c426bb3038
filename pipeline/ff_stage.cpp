#include "pipeline/ff_stage.hpp"

#include <algorithm>
#include <cstdio>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "geometry/formfactors/analysis.hpp"
#include "geometry/media/medium.hpp"
#include "io/ff_file.hpp"
#include "io/ff_settings.hpp"

namespace lambert {

void plan_form_factors(JobPlan& plan, const FormFactorArgs& args, const RunArgs& run,
                       bool with_stderr) {
  if (!args.ff_file.empty()) {
    plan.inputs.push_back({"--ff", args.ff_file});
    return;
  }
  plan.ff = make_ff_options(args, run);
  plan.ff->run.with_stderr = with_stderr;
}

std::string selected_estimator(const FormFactorArgs& args) {
  return args.ff_file.empty() ? args.estimator : "";
}

double FormFactorArgs::param(const std::string& option) const {
  const auto it = params.find(option);
  if (it != params.end()) return it->second;
  const DeclaredEstimatorParam* d = find_estimator_param(option);
  LAMBERT_CHECK(d != nullptr, "no estimator declares the parameter " + option);
  return d->param.fallback;
}

void FormFactorArgs::set_param(const std::string& option, double value) {
  LAMBERT_CHECK(find_estimator_param(option) != nullptr,
                "no estimator declares the parameter " + option);
  params[option] = value;
  params_given.insert(option);
}

std::string estimator_readers_text(const std::vector<std::string>& estimators) {
  std::string out = estimators.size() == 1 ? "the estimator " : "the estimators ";
  for (size_t k = 0; k < estimators.size(); ++k)
    out += (k == 0 ? "" : k + 1 == estimators.size() ? " and " : ", ") + estimators[k];
  return out;
}

namespace {

std::string readers_of(const std::string& option) {
  const DeclaredEstimatorParam* d = find_estimator_param(option);
  return d ? estimator_readers_text(d->estimators) : "";
}

}  // namespace

FormFactorOptions make_ff_options(const FormFactorArgs& args, const RunArgs& run) {
  FormFactorOptions o;
  o.estimator = args.estimator;
  for (const auto& [option, value] : args.params) set_estimator_param(o, option, value);
  o.run.seed = run.seed;
  o.run.threads = run.threads;
  o.threshold = args.threshold;
  o.reciprocity = args.symmetrize ? "average" : args.reciprocity;
  o.run.progress = !run.quiet;
  o.specular.depth = args.specular_depth;
  o.specular.rays = args.specular_rays;
  o.analytic.tol_given = args.given("--ff-tol");
  if (args.estimator != "auto") {
    const std::vector<std::string> unused = unused_count_options(args, args.estimator);
    if (!unused.empty())
      throw UsageError(unused.front() + " does not apply to --estimator " + args.estimator +
                       " (read by " + readers_of(unused.front()) + ")");
  }
  return o;
}

void check_auto_pick(const FormFactorArgs& args, std::int64_t patches) {
  if (args.estimator != "auto") return;
  const std::string pick = auto_estimator(patches, args.given("--ff-tol"));
  const std::vector<std::string> unused = unused_count_options(args, pick);
  if (args.reciprocity_given && pick != "gather")
    throw UsageError((args.symmetrize ? "--symmetrize" : "--reciprocity") +
                     std::string(" does not apply: --estimator auto picks ") + pick + " for " +
                     std::to_string(patches) +
                     " patches, whose F is reciprocal by construction (gather and hemicube "
                     "read it)");
  if (!unused.empty())
    throw UsageError(unused.front() + " does not apply: --estimator auto picks " + pick + " for " +
                     std::to_string(patches) + " patches (name the estimator that reads it: " +
                     readers_of(unused.front()) + ")");
}

void check_ff_args_for_mesh(const FormFactorArgs& args, const PatchMesh& mesh) {
  check_auto_pick(args, mesh.size());
  if (args.specular_given && !mesh.has_specular())
    throw UsageError(
        "--specular-depth and --specular-rays do not apply: the scene has no mirror or glass "
        "surface (MTL illum 3 to 9)");
}

std::vector<std::string> unused_count_options(const FormFactorArgs& args,
                                              const std::string& estimator) {
  std::vector<std::string> out;
  for (const DeclaredEstimatorParam& d : estimator_params())
    if (args.given(d.param.option) &&
        std::find(d.estimators.begin(), d.estimators.end(), estimator) == d.estimators.end())
      out.push_back(d.param.option);
  return out;
}

namespace {

// "form factors: auto picked gather (N patches >= T)".
void log_auto_pick(const FormFactors& ff, std::int32_t patches) {
  if (ff.options.estimator_requested != "auto") return;
  const std::string n = std::to_string(patches) + " patches";
  const std::string why =
      ff.options.estimator == "analytic"
          ? "--ff-tol given, " + n + " <= " + std::to_string(kAutoAnalyticMaxPatches)
          : n + (ff.options.estimator == "gather" ? " >= " : " < ") +
                std::to_string(kAutoGatherPatches) +
                (ff.options.analytic.tol_given
                     ? "; analytic only up to " + std::to_string(kAutoAnalyticMaxPatches) +
                           " patches, name it to force it"
                     : "");
  log_info("form factors: auto picked " + ff.options.estimator + " (" + why + ")");
}

// ", reciprocity averaged (...)" for the summary line, or "".
std::string reciprocity_summary(const FormFactors& ff) {
  if (ff.options.reciprocity != "average") return "";
  char buf[240];
  std::snprintf(buf, sizeof buf,
                ", reciprocity averaged (change max %.3g, mean %.3g; balanced in %d sweeps, "
                "pair scale %.4g-%.4g; %lld rows capped at 1)",
                ff.stats.reciprocity_max_relative_change, ff.stats.reciprocity_mean_relative_change,
                ff.stats.reciprocity_balance_iterations, ff.stats.reciprocity_scale_min,
                ff.stats.reciprocity_scale_max,
                static_cast<long long>(ff.stats.reciprocity_rows_scaled));
  return buf;
}

}  // namespace

namespace {

// A loaded F that holds a participating medium's zones must be used with that medium: the
// zones' albedo and emission come from the medium options, their exchange factors from the
// file. Its extinction hash (medium.hpp) names the medium it was computed for.
void check_loaded_medium(const FormFactors& ff, const Medium* medium, const std::string& path) {
  const FormFactorOptions& o = ff.options;
  if (o.contents.medium_zones == 0) return;
  if (medium == nullptr)
    throw UsageError(path + ": holds the exchange factors of a participating medium (" +
                     std::to_string(o.contents.medium_zones) +
                     " zones): give the medium it was computed with (--medium-box with "
                     "--sigma-a/--sigma-s, or --medium-grid)");
  if (extinction_hash(*medium) != o.contents.medium_extinction)
    throw SceneError(path + ": computed for another participating medium (" +
                     std::to_string(o.contents.medium_zones) +
                     " zones; its box, voxels or extinction sigma_a + sigma_s differ from the "
                     "medium given): give the same medium, or a form-factor file without one");
}

}  // namespace

FormFactors obtain_form_factors(const LoadedScene& scene, const FormFactorArgs& args,
                                const RunArgs& run, bool with_stderr, const Medium* medium) {
  if (!args.ff_file.empty()) {
    FormFactorFileInfo info;
    FormFactors ff =
        read_form_factors(args.ff_file, mesh_hash(scene.mesh), scene.mesh.size(), &info);
    ff.options.run.threads = run.threads;
    ff.options.run.progress = !run.quiet;
    ff.options.run.with_stderr = ff.stderr_F.nonZeros() > 0;
    if (!parse_ff_settings(info.settings, ff.options)) {
      ff.options.estimator.clear();
      log_warn(args.ff_file + ": records no form-factor settings; reports show them as unknown");
    }
    if (ff.options.contents.extended && ff.specular_continued.size() != ff.F.rows())
      log_warn(args.ff_file +
               ": extended form factors without their specular bookkeeping "
               "(a Matrix Market file): the energy balance counts light carried on by mirrors "
               "and glass once more, as negative escaped power (save F as .bin to keep it)");
    check_loaded_medium(ff, medium, args.ff_file);
    log_info("form factors: loaded " + args.ff_file + " (" + std::to_string(ff.F.nonZeros()) +
             " entries, " + ff_settings_text(ff.options, "") + ")");
    return ff;
  }
  check_ff_args_for_mesh(args, scene.mesh);
  FormFactorOptions o = make_ff_options(args, run);
  o.run.with_stderr = with_stderr;
  FormFactors ff = compute_form_factors(scene.mesh, o, &scene_bvh(scene, run.threads));
  log_auto_pick(ff, scene.mesh.size());
  log_info("form factors: " + std::to_string(scene.mesh.size()) + " patches, " +
           format_si(static_cast<double>(ff.F.nonZeros())) + " entries, " +
           format_si(static_cast<double>(ff.stats.rays)) + " rays in " +
           format_duration(ff.stats.seconds) + reciprocity_summary(ff) +
           (ff.options.contents.extended ? ", " + format_si(static_cast<double>(ff.stats.specular_rays)) +
                                      " of them on specular paths (depth " +
                                      std::to_string(ff.options.specular.depth) + ")"
                                : ""));
  if (ff.stats.pairs_short_of_target > 0)
    log_warn(std::to_string(ff.stats.pairs_short_of_target) + " of " +
             std::to_string(ff.stats.pairs_tested) +
             " patch pairs stayed above --target-stderr at " + std::to_string(kMaxPairSamples) +
             " samples (their entries carry larger errors; --stderr shows them): raise the "
             "target or mesh more coarsely");
  if (ff.stats.pairs_unverified > 0) {
    // The size of the effect: the share of the pairs and of the exchange Σ A_i F_ij.
    const double exchange = unverified_exchange_share(ff, scene.mesh);
    const std::string pairs = std::to_string(ff.stats.pairs_unverified) +
                              (ff.stats.pairs_unverified == 1 ? " patch pair" : " patch pairs");
    char share[160];
    std::snprintf(share, sizeof share,
                  " (%.3g %% of the %lld pairs, carrying %.3g %% of the exchange)",
                  100.0 * static_cast<double>(ff.stats.pairs_unverified) /
                      static_cast<double>(std::max<std::int64_t>(ff.stats.pairs_tested, 1)),
                  static_cast<long long>(ff.stats.pairs_tested), 100.0 * exchange);
    if (ff.options.estimator == "analytic")
      log_warn(pairs + share +
               " did not reach --ff-tol, neither within their budget of point factors nor by "
               "sampling to 2^20 rays: their entries "
               "carry a larger error estimate (--stderr shows it); many blockers per pair or "
               "blockers standing on both patches are the likely cause (docs/form-factors.md "
               "\"The analytic estimator\": hybrid or gather suit such scenes)");
    else
      // Below 1e-4 of the exchange the effect is far under the Monte Carlo estimators' own
      // error (a few % per entry at the default samples, ~1e-3 on a row sum): a note, not a
      // warning (the default Cornell run had 4 such pairs carrying 1e-8 of it).
      (exchange > 1e-4 ? log_warn : log_info)(
          pairs + share +
          " could not have their visibility sampled as designed (no ray could be traced, "
          "or the kernel sampler gave up): their factors are unoccluded values or "
          "approximate; a degenerate (sliver or grazing) patch is the likely cause");
  }
  return ff;
}

double unverified_exchange_share(const FormFactors& ff, const PatchMesh& mesh) {
  double total = 0.0;
  for (std::int32_t i = 0; i < std::min<std::int64_t>(ff.F.outerSize(), mesh.size()); ++i)
    for (SparseF::InnerIterator it(ff.F, i); it; ++it) total += mesh.patches[i].area * it.value();
  return total > 0.0 ? ff.stats.unverified_exchange / total : 0.0;
}

void warn_about_lighting(const PatchMesh& mesh, const SparseF& F) {
  LightingProblems p = find_lighting_problems(mesh, F);
  p.no_emitter = false;  // the scene loader has warned already, naming the file and --emit
  for (const std::string& line : lighting_warnings(mesh, p)) log_warn(line);
}

void check_closed_lossless(const PatchMesh& mesh, const FormFactors& ff, bool solving) {
  const std::vector<ClosedLossless> sets = find_closed_lossless(mesh, ff);
  if (sets.empty()) return;
  if (solving) throw SceneError(closed_lossless_message(mesh, sets.front()));
  for (const auto& c : sets)
    log_warn(closed_lossless_message(mesh, c) + " (a solve with this F is refused)");
}

Json ff_settings_json(const FormFactorOptions& o, const std::string& loaded_from) {
  Json j = ff_settings_report(o);
  j["loaded_from"] = loaded_from;
  return j;
}

Json reciprocity_json(const FormFactors& ff) {
  const FormFactorStats& st = ff.stats;
  return {{"applied", ff.options.reciprocity == "average"},
          {"max_relative_change", st.reciprocity_max_relative_change},
          {"mean_relative_change", st.reciprocity_mean_relative_change},
          {"rows_scaled", st.reciprocity_rows_scaled},
          {"balance_iterations", st.reciprocity_balance_iterations},
          {"scale_min", st.reciprocity_scale_min},
          {"scale_max", st.reciprocity_scale_max},
          {"max_row_sum_before", st.reciprocity_max_row_sum}};
}

std::string ff_settings_text(const FormFactorOptions& o, const std::string& loaded_from) {
  return (loaded_from.empty() ? std::string() : "ff=" + loaded_from + " ") +
         (o.estimator.empty() ? std::string("settings=unknown") : format_ff_settings(o));
}

}  // namespace lambert
