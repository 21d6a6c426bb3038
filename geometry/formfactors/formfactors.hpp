#pragma once
// Form-factor estimation: the registry of estimators and the shared result type.
//
// F_ij = (1/A_i) ∫_{A_i} ∫_{A_j} V(x,y) cosθ_x cosθ_y / (π r²) dA_y dA_x  (dimensionless),
// the fraction of the power leaving patch i (front side, diffusely) that arrives at patch j.

#include <Eigen/SparseCore>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/sparse.hpp"
#include "geometry/mesh/mesh.hpp"

namespace lambert {

/// Row-major sparse form-factor matrix: row i holds F_ij for every j patch i sees.
using SparseF = SparseRowMatrix;

/// Parameters of the sampling pair estimators (mc, hybrid; also the sensor-point factors of
/// analysis.hpp).
struct PairEstimatorParams {
  int samples = 32;  ///< sample pairs (rays) per patch pair
};

/// The most samples per pair (--samples, and where --target-stderr stops).
constexpr int kMaxPairSamples = 1 << 20;

/// Parameters of the estimator "gather".
struct GatherParams {
  int rays = 1024;  ///< rays per patch
};

/// Parameters of the estimator "hemicube".
struct HemicubeParams {
  int resolution = 128;  ///< top-face resolution (pixels per side)
};

/// Parameters of the estimator "analytic" (and of "auto", which tol_given steers).
struct AnalyticParams {
  /// Absolute error target of every entry F_ij (its quadrature error estimate, reported as
  /// the standard error).
  double tol = 1e-6;
  /// The user asked for `tol` (--ff-tol): "auto" then picks analytic, the one estimator that
  /// honours an error target (docs/form-factors.md, "Choosing an estimator").
  bool tol_given = false;
};

/// Extended form factors (specular.hpp), read by every estimator that traces rays (mc,
/// hybrid, gather) when the mesh has specular surfaces.
struct SpecularParams {
  /// The most specular bounces a path follows (0: specular surfaces only receive and block).
  int depth = 8;
  int rays = 1024;  ///< cosine rays per patch that trace the paths with at least one bounce
};

/// How a computation runs, read by every estimator: the seed of its random streams, and what
/// does not change the values of F (for a given seed they are bitwise identical for any
/// thread count).
struct FormFactorRun {
  std::uint64_t seed = 1;    ///< the random streams' seed (core/sampling.hpp: hash_keys)
  int threads = 0;           ///< 0 = all cores
  bool progress = true;      ///< draw a progress bar (when stderr is a terminal)
  bool with_stderr = false;  ///< also estimate the standard error of each entry
};

/// Which entries to compute (default: all of F), for updates and distributed runs.
struct FormFactorSubset {
  /// Incremental updates (adaptive meshing): when non-empty (one flag per patch), only the
  /// pairs with a flagged patch are estimated (pair estimators: both entries of each such
  /// pair; gather and hemicube: the flagged rows); everything else is left empty, and
  /// reciprocity averaging and the threshold are not applied (see update_form_factors).
  std::vector<char> only;
  /// Distributed form factors (docs/cluster.md): when row_end > row_begin,
  /// a pair estimator computes only the pairs (i, j > i) with i in [row_begin, row_end),
  /// each with the stream it has in a whole computation, and returns both of their entries
  /// (F_ij and F_ji: rows outside the range receive mirrors), the threshold applied per
  /// pair. Row estimators, reciprocity averaging and specular paths refuse a range (they
  /// need whole columns). The default [0, 0) is every row.
  std::int32_t row_begin = 0;
  std::int32_t row_end = 0;
};

/// What F holds besides the patches' diffuse exchange: set on a result (and read back from
/// a saved F's settings), never read by an estimator.
struct FormFactorContents {
  /// F holds the specular paths (the mesh had specular surfaces and specular.depth > 0).
  bool extended = false;
  /// Set by extend_with_medium (media.hpp): F also holds the medium's zones, rows and
  /// columns N..N+medium_zones-1 (0: no medium). The extinction hash (medium.hpp:
  /// extinction_hash) names the medium the zones came from; medium_rays and
  /// transmittance_samples are its settings.
  std::int32_t medium_zones = 0;
  std::uint64_t medium_extinction = 0;
  int medium_rays = 0;
  int transmittance_samples = 0;
};

/// The parameters of the estimators that have no block of their own in FormFactorOptions:
/// option name ("--foo") -> value (an integer parameter holds a whole number). A name that is
/// absent is at its declared default (EstimatorParam::fallback; estimator_param reads it).
using EstimatorParamValues = std::map<std::string, double>;

/// Settings of one form-factor computation: the choice of estimator and what applies to
/// every estimator, and one block per estimator's own parameters.
struct FormFactorOptions {
  /// A name from form_factor_estimators(), or "auto" (resolve_form_factor_options: analytic
  /// when analytic.tol_given on up to kAutoAnalyticMaxPatches patches, else hybrid below
  /// kAutoGatherPatches patches, gather at or above).
  std::string estimator = "auto";
  /// What was asked for when `estimator` was resolved from "auto" ("" when it was named).
  std::string estimator_requested;
  double threshold = 0.0;  ///< drop entries with F_ij < threshold (after estimation)
  /// "average": replace A_i F_ij and A_j F_ji by their mean (reciprocity.hpp); "none";
  /// "auto": average for gather, none for the others (the pair estimators are reciprocal by
  /// construction; the hemicube keeps its historical default, --symmetrize to average).
  std::string reciprocity = "auto";
  PairEstimatorParams pair;     ///< read by mc and hybrid
  GatherParams gather;          ///< read by gather
  HemicubeParams hemicube;      ///< read by hemicube
  AnalyticParams analytic;      ///< read by analytic (and auto)
  /// Read by the estimators whose parameters have no block above (estimator_param): a new
  /// estimator's parameters live here, declared on its registry entry.
  EstimatorParamValues params;
  SpecularParams specular;      ///< read by mc, hybrid and gather on a mesh with mirrors or glass
  FormFactorRun run;            ///< read by every estimator
  FormFactorSubset subset;      ///< read by every estimator (a row range: the pair estimators)
  FormFactorContents contents;  ///< written on the result
};

/// What a computation did (for diagnostics and reports).
struct FormFactorStats {
  /// Unordered pairs that can exchange energy (gather: that at least one ray connected)
  std::int64_t pairs_tested = 0;
  std::int64_t pairs_culled = 0;  ///< the other unordered pairs (facing away; gather: unseen)
  std::int64_t rays = 0;          ///< rays traced (occlusion; gather: closest-hit, N·K)
  /// Pairs whose visibility could not be sampled as designed (hybrid: no ray could be
  /// traced, so the unoccluded value was kept; or a kernel-sampling rejection gave up), or
  /// (analytic) whose integral stopped at its budget before --ff-tol: reported and warned
  /// about, expected 0.
  std::int64_t pairs_unverified = 0;
  /// Σ A_i F_ij + A_j F_ji of those pairs (scene units²): with the total exchange
  /// Σ_i A_i Σ_j F_ij, the share of F they carry (the size of the warning's effect).
  double unverified_exchange = 0.0;
  /// Pairs (mc, hybrid with --target-stderr) whose standard error was still above the
  /// target at kMaxPairSamples samples.
  std::int64_t pairs_short_of_target = 0;
  double seconds = 0.0;           ///< wall time of the computation
  /// Reciprocity averaging (0 when not applied; see reciprocity.hpp), of its averaging step
  /// alone (G = A_i F_ij before, G' = (A_i F_ij + A_j F_ji) / 2): the largest relative change
  /// |G' - G| / G of an entry that was present, and the G-weighted mean Σ|G' - G| / ΣG over
  /// all entries (created mirrors, G = 0, count in the numerator).
  double reciprocity_max_relative_change = 0.0;
  double reciprocity_mean_relative_change = 0.0;
  /// The smallest and largest factor d_i d_j min(s_i, s_j) by which balancing and the cap
  /// scaled an averaged pair (1 = untouched).
  double reciprocity_scale_min = 0.0;
  double reciprocity_scale_max = 0.0;
  /// Rows still above 1 after balancing, scaled down by the cap, and the largest row sum
  /// before the cap; balancing sweeps made.
  std::int64_t reciprocity_rows_scaled = 0;
  double reciprocity_max_row_sum = 0.0;
  int reciprocity_balance_iterations = 0;
  double reciprocity_seconds = 0.0;  ///< wall time of the averaging (included in seconds)
  /// Ray segments of the extended form factors' specular paths (included in rays).
  std::int64_t specular_rays = 0;
};

/// The estimated matrix, optionally with per-entry standard errors (same sparsity).
/// Moves are cheap: Eigen 3.4's SparseMatrix has no move constructor (std::move copies it),
/// so FormFactors moves its matrices by swapping.
struct FormFactors {
  SparseF F;
  SparseF stderr_F;  ///< empty (0 x 0) unless with_stderr
  /// Extended form factors (specular.hpp): per row, the weight carried on specularly past
  /// the arrivals counted in F; empty for a purely diffuse mesh (then it is all zero).
  Eigen::VectorXd specular_continued;
  FormFactorStats stats;
  FormFactorOptions options;  ///< the settings that produced F

  FormFactors() = default;
  FormFactors(const FormFactors&) = default;
  FormFactors& operator=(const FormFactors&) = default;
  FormFactors(FormFactors&& other) noexcept { *this = std::move(other); }
  FormFactors& operator=(FormFactors&& other) noexcept {
    F.swap(other.F);
    stderr_F.swap(other.stderr_F);
    specular_continued.swap(other.specular_continued);
    stats = other.stats;
    options = std::move(other.options);
    return *this;
  }
};

class Bvh;

/// One parameter of an estimator, declared once on its registry entry
/// (FormFactorEstimator::params). From it come the CLI option and its check, --help line and
/// default (apps/options.cpp), its row in option_specs() (pipeline/option_specs.cpp: the
/// option reference, and "does not apply" for an estimator that does not declare it), the
/// Python keyword and its docstring line (python/), and its key in the settings text stored
/// with a saved F and in the reports (io/ff_settings.cpp). Build one with integer_param or
/// real_param; the defaults suit a new parameter (its value in FormFactorOptions::params,
/// stored in the settings text when the estimator reads it).
struct EstimatorParam {
  std::string option;         ///< the CLI option, "--samples"
  std::string keyword;        ///< the Python keyword, the settings key and the report name
  bool integer = true;        ///< a whole number (else a finite real number)
  double lo = 0.0, hi = 0.0;  ///< the accepted range [lo, hi] (open at lo when open_lo)
  bool open_lo = false;
  double fallback = 0.0;  ///< the default
  std::string doc;        ///< the one-line description (--help, docs/options.md, Python)
  std::string alias;      ///< another name the formfactors command takes ("--tol"; "" = none)

  // The settings text (io/ff_settings.hpp). Keys are only ever added: saved files and their
  // readers depend on the text byte for byte.
  std::string key;     ///< the settings text's key ("" = `keyword`)
  std::string report;  ///< the name in reports ("" = `keyword`)
  /// Stored whatever the estimator, after the setting `after` (the parameters stored since
  /// the first files: samples, rays, hemicube_res). Otherwise (the default) stored when the
  /// estimator reads it, after the specular settings.
  bool stored_always = false;
  /// The setting (key or report name) it follows in the table, hence in reports and, stored
  /// always, in the text ("" = after the others).
  std::string after;
  bool required = false;  ///< a settings text without it is refused (samples)
  /// An integer parameter: the range a settings text's value must be in (both 0: [lo, hi]);
  /// a saved value may be outside the command line's range (files from the library). A real
  /// one's must be finite, and positive when the range is.
  double stored_min = 0.0, stored_max = 0.0;

  /// Where the value lives: a member of one of FormFactorOptions' blocks (the parameters that
  /// predate this table, which the estimators read by name), or, left null, `params`.
  double (*get)(const FormFactorOptions&) = nullptr;
  void (*set)(FormFactorOptions&, double) = nullptr;
};

/// A parameter taking whole numbers in [lo, hi], `fallback` by default.
EstimatorParam integer_param(std::string option, std::string keyword, double lo, double hi,
                             double fallback, std::string doc);

/// A parameter taking finite real numbers in [lo, hi] (> lo when open_lo), `fallback` by
/// default.
EstimatorParam real_param(std::string option, std::string keyword, double lo, double hi,
                          double fallback, std::string doc, bool open_lo = false);

/// One estimator: a row of the registry (formfactors.cpp), or one added by
/// register_form_factor_estimator.
struct FormFactorEstimator {
  std::string name;  ///< the --estimator value
  /// Computes each unordered pair once (compute_pairwise): accepts a row range.
  bool pairwise = false;
  /// Traces rays: reports replicate standard errors (needs count >= 4); follows mirrors.
  bool traces_rays = false;
  bool uses_bvh = false;     ///< queries a BVH (rays, or the analytic estimator's blocker search)
  std::string count_option;  ///< "samples", "rays", "tol" or "" (estimator_count_option)
  /// "auto" reciprocity averages: gather (noisy one-sided rows; averaging halves the variance
  /// of a pair and makes F reciprocal). Not the pair estimators (reciprocal by construction)
  /// nor the hemicube (its non-reciprocity is a result `accuracy` studies).
  bool auto_average = false;
  /// Computes F (every row, or the pairs FormFactorSubset selects); `bvh` is built over the
  /// mesh when uses_bvh, else null. compute_form_factors checks the parameters first.
  FormFactors (*compute)(const PatchMesh&, const FormFactorOptions&, const Bvh* bvh) = nullptr;
  /// Upper bound (bytes) of the computation's memory (form_factor_peak_bytes).
  double (*peak_bytes)(std::int64_t patches, const FormFactorOptions&) = nullptr;
  /// The parameters it reads (one may be shared: mc and hybrid both declare --samples).
  std::vector<EstimatorParam> params;
};

/// Adds an estimator to the registry (a plug-in, or a test's double). Call it before the
/// first use of the registry or of the option table (a static initialiser): the CLI, the
/// option reference and Python read the registry once. A name already registered, or a
/// parameter that differs from another estimator's of the same option, is a bug
/// (LAMBERT_CHECK).
void register_form_factor_estimator(FormFactorEstimator estimator);

/// The registry: every estimator, in the order --estimator lists them.
const std::vector<FormFactorEstimator>& form_factor_estimator_table();

/// An estimator parameter once, with the estimators that declare it (registry order).
struct DeclaredEstimatorParam {
  EstimatorParam param;
  std::vector<std::string> estimators;
};

/// Every estimator parameter once, in registry order (an estimator's in its order).
const std::vector<DeclaredEstimatorParam>& estimator_params();

/// The declaration of the estimator parameter `option` ("--samples"), or nullptr.
const DeclaredEstimatorParam* find_estimator_param(const std::string& option);

/// The value of the estimator parameter `option` in `options` (its block's member, or
/// `params`, or its default). An undeclared option is a bug (LAMBERT_CHECK).
double estimator_param(const FormFactorOptions& options, const std::string& option);

/// Sets the estimator parameter `option` (an integer one is rounded to the nearest whole
/// number). An undeclared option is a bug (LAMBERT_CHECK).
void set_estimator_param(FormFactorOptions& options, const std::string& option, double value);

/// Names of the available estimators ("mc", "hybrid", ...); "auto" is not one of them.
std::vector<std::string> form_factor_estimators();

/// The --estimator choices: form_factor_estimators() and "auto".
std::vector<std::string> form_factor_estimator_choices();

/// `--estimator auto` picks "gather" at or above this many patches and "hybrid" below.
/// Measured on the Cornell box (2 cores, docs/form-factors.md): hybrid's O(N²)
/// pairs take about a minute at this size, gather's O(N·K) rays about a second.
constexpr std::int64_t kAutoGatherPatches = 6000;

/// `--estimator auto` with `--ff-tol` picks "analytic" up to this many patches. Its O(N²)
/// pairs cost 0.1-10 ms each on plates and panels and up to seconds with boxes standing on
/// the faces (docs/form-factors.md, "The analytic estimator"): 500 patches are 125k pairs, minutes
/// for a clean enclosure. Above it, auto ignores --ff-tol with a warning (name the estimator to
/// force it).
constexpr std::int64_t kAutoAnalyticMaxPatches = 500;

/// Splits the rows of an n-patch pair computation into `parts` consecutive ranges of about
/// equal cost, the cost of row i being its n - 1 - i pairs (i, j > i): returns parts + 1
/// first rows (0, ..., n). Deterministic; independent of threads. O(parts).
std::vector<std::int32_t> balanced_pair_rows(std::int32_t n, int parts);

/// True when `estimator` (a name from form_factor_estimators()) computes each unordered
/// pair once (mc, hybrid, analytic), the estimators that accept a row range.
bool is_pair_estimator(const std::string& estimator);

/// The estimator "auto" stands for at `patches` patches: "analytic" when an error target was
/// given (`analytic.tol_given`) and patches <= kAutoAnalyticMaxPatches, else by kAutoGatherPatches.
std::string auto_estimator(std::int64_t patches, bool tol_given);

/// Which per-count option an estimator reads: "samples" (pair estimators), "rays"
/// (gather), "tol" (analytic: --ff-tol) or "" (hemicube). Throws UsageError for an unknown name (not "auto").
std::string estimator_count_option(const std::string& estimator);

/// `options` with "auto" resolved for `patches` patches: estimator (estimator_requested
/// then keeps "auto") and reciprocity ("none" or "average"). Throws UsageError for an
/// unknown estimator or reciprocity mode.
FormFactorOptions resolve_form_factor_options(const FormFactorOptions& options,
                                              std::int64_t patches);

/// Upper bound (bytes) on the memory compute_form_factors needs for `patches` patches with
/// these options, before any work: the all-pairs estimators from the N(N-1)/2 pair bound, the
/// hemicube from at most one entry per pixel per row, gather from at most K entries per row
/// ("auto" is resolved first). --threshold prunes only after the
/// estimate, so it does not lower the peak. Throws UsageError for an unknown estimator.
double form_factor_peak_bytes(std::int64_t patches, const FormFactorOptions& options);

/// Computes F for every patch pair of `mesh` with the chosen estimator. Multi-threaded;
/// for a given seed the result is bitwise identical for any thread count. `bvh` (built over
/// `mesh`) is used for the visibility rays when given, so that one BVH serves a whole run;
/// otherwise one is built. "auto" settings are resolved first (the result's `options`
/// hold the resolved ones), and reciprocity averaging is applied last. Throws UsageError for an unknown estimator or invalid settings.
FormFactors compute_form_factors(const PatchMesh& mesh, const FormFactorOptions& options,
                                 const Bvh* bvh = nullptr);

/// F on a refined mesh from F on the mesh it was refined from: `origin[i]` is the old
/// index of new patch i when it is unchanged (the same polygon), -1 when it is new. Entries
/// between unchanged patches are copied from `old_F`; the pairs with a new patch are
/// estimated (FormFactorSubset::only) and, where both sides are estimated (pair
/// estimators; a row estimator's two new rows), their G = A F is averaged, so that
/// A_i F_ij = A_j F_ji holds for them; a row estimator's new row also gives the unchanged
/// row its column (F_ji = A_i F_ij / A_j). Cost: O(changed x N) estimates, not O(N²).
FormFactors update_form_factors(const PatchMesh& mesh, const std::vector<std::int32_t>& origin,
                                const SparseF& old_F, const FormFactorOptions& options,
                                const Bvh* bvh = nullptr);

}  // namespace lambert
