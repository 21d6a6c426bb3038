#include "geometry/formfactors/formfactors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/assembly.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/gather.hpp"
#include "geometry/formfactors/hemicube.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/reciprocity.hpp"
#include "geometry/formfactors/specular.hpp"

namespace lambert {

namespace ff {


// Rows are estimated in blocks of about 1/kBlocks of the pairs, in parallel within a block;
// each block's upper-triangle entries (G_ij, j > i) are then appended in row order to the
// CSR that becomes F (assembly.hpp), and mirror_upper completes it in place. Staging is one
// block of rows.
constexpr std::int64_t kBlocks = 64;

// --target-stderr s: the pair is estimated again with 4 times the samples (the error halves)
// until its error -- the larger of F_ij's and F_ji's, sqrt(var) / min(A_i, A_j) -- is at most
// s, or the samples reach kMaxPairSamples (then it is counted short of the target). Where
// the rays all agree (every one seen, or none) the replicates have no spread to read, yet a
// visible fraction from n rays only resolves 1/n: the error is taken as at least the pair's
// larger unoccluded factor (its centroids' point factors stand for it) over n. Each estimate
// uses the pair's own stream, so the result does not depend on the thread count; the last
// one is kept (the rule reads its spread, not its mean: a bias of the order of its variance).
PairEstimate estimate_to_target(const PairContext& ctx, PairEstimator estimator, std::int32_t i,
                                std::int32_t j, double target) {
  const PatchGeom &a = ctx.geom[i], &b = ctx.geom[j];
  const double area = std::min(a.area, b.area);
  const double unoccluded =
      std::max(point_to_patch(a.centroid, a.normal, b), point_to_patch(b.centroid, b.normal, a));
  auto error = [&](const PairEstimate& e, int samples) {
    return std::max(std::sqrt(e.var) / area,
                    std::max(unoccluded, e.G / area) / static_cast<double>(samples));
  };
  PairContext c = ctx;
  PairEstimate e = estimator(c, i, j);
  std::int64_t rays = e.rays;
  while (error(e, c.samples) > target && c.samples < kMaxPairSamples) {
    c.samples = static_cast<int>(std::min<std::int64_t>(4LL * c.samples, kMaxPairSamples));
    e = estimator(c, i, j);
    rays += e.rays;
  }
  e.rays = rays;
  e.short_of_target = error(e, c.samples) > target;
  return e;
}

FormFactors compute_pairwise(const PatchMesh& mesh, const FormFactorOptions& options,
                             const Bvh& bvh, PairEstimator estimator) {
  Timer timer;
  const std::int32_t n = mesh.size();
  const std::vector<PatchGeom> geom = patch_geometry(mesh);
  const PairContext ctx{geom,
                        bvh,
                        options.pair.samples,
                        options.run.seed,
                        kRayOffset * mesh.scale,
                        options.analytic.tol};
  const double plane_eps = kPlaneEps * mesh.scale;
  const double target = estimator_param(options, "--target-stderr");
  const std::int64_t total_pairs = static_cast<std::int64_t>(n) * (n - 1) / 2;
  // A row range (distributed form factors) computes the pairs of rows [first, last) only;
  // every pair keeps its stream hash_keys(seed, i, j), so its entries are the same doubles.
  const bool ranged = options.subset.row_end > options.subset.row_begin;
  const std::int32_t first = ranged ? options.subset.row_begin : 0;
  const std::int32_t last = ranged ? options.subset.row_end : n;
  auto pairs_before = [n](std::int64_t i) { return i * (n - 1) - i * (i - 1) / 2; };
  const std::int64_t range_pairs = pairs_before(last) - pairs_before(first);

  // Room for every pair of the range in both triangles; pages of pairs that do not exchange
  // energy are never written, so they cost address space only.
  CsrAppender upper(n, 2 * range_pairs, options.run.with_stderr);
  std::vector<std::vector<RowEntry>> rows(n);
  std::vector<std::int64_t> tested(n, 0), rays(n, 0), unverified(n, 0), short_of(n, 0);
  std::vector<double> unverified_g(n, 0.0);
  Progress progress("form factors", options.run.progress ? range_pairs : 0, "rays");
  const std::int64_t block_pairs = std::max<std::int64_t>(1, total_pairs / kBlocks);
  for (std::int32_t i = 0; i < first; ++i) upper.append_row({});
  for (std::int32_t block_begin = first; block_begin < last;) {
    std::int32_t block_end = block_begin;
    for (std::int64_t pairs = 0; block_end < last && pairs < block_pairs; ++block_end)
      pairs += n - 1 - block_end;
    // The block's pairs (i, j > i) in row order, in parallel pair by pair (a room's floor
    // row alone can outweigh the others: rows as the unit left one thread on it); each pair
    // writes its own slot, gathered into the rows in order below.
    std::vector<std::int64_t> offset(1, 0);  // per row of the block, its first pair
    for (std::int32_t i = block_begin; i < block_end; ++i)
      offset.push_back(offset.back() + n - 1 - i);
    const std::int64_t count = offset.back();
    std::vector<PairEstimate> slot(static_cast<size_t>(count));
    std::vector<char> done(static_cast<size_t>(count), 0);
    const std::int64_t chunk = std::max<std::int64_t>(
        1, count / (64 * static_cast<std::int64_t>(resolve_threads(options.run.threads))));
    parallel_for(count, chunk, options.run.threads, [&](std::int64_t begin, std::int64_t end) {
      std::int64_t chunk_rays = 0;
      for (std::int64_t k = begin; k < end; ++k) {
        const auto r = std::upper_bound(offset.begin(), offset.end(), k) - offset.begin() - 1;
        const auto i = static_cast<std::int32_t>(block_begin + r);
        const auto j = static_cast<std::int32_t>(i + 1 + (k - offset[r]));
        const bool all = options.subset.only.empty();
        if (!all && !options.subset.only[i] && !options.subset.only[j]) continue;
        if (!can_exchange(geom[i], geom[j], plane_eps)) continue;
        slot[k] =
            target > 0.0 ? estimate_to_target(ctx, estimator, i, j, target) : estimator(ctx, i, j);
        done[k] = 1;
        chunk_rays += slot[k].rays;
      }
      progress.advance(end - begin, chunk_rays);
    });
    for (std::int32_t i = block_begin; i < block_end; ++i) {
      const std::int64_t r = i - block_begin;
      std::int64_t row_rays = 0;
      for (std::int64_t k = offset[r]; k < offset[r + 1]; ++k) {
        if (!done[k]) continue;
        const PairEstimate& e = slot[k];
        const auto j = static_cast<std::int32_t>(i + 1 + (k - offset[r]));
        ++tested[i];
        row_rays += e.rays;
        unverified[i] += e.unverified;
        short_of[i] += e.short_of_target;
        if (e.unverified) unverified_g[i] += 2.0 * e.G;  // both entries of the pair
        if (e.G > 0.0) rows[i].push_back({j, e.G, e.var});
      }
      rays[i] = row_rays;
    }
    upper.append_rows(rows.data() + block_begin, block_end - block_begin, options.run.threads);
    for (std::int32_t i = block_begin; i < block_end; ++i)
      std::vector<RowEntry>().swap(rows[i]);  // release the staging as we go
    block_begin = block_end;
  }
  for (std::int32_t i = last; i < n; ++i) upper.append_row({});
  progress.finish();

  FormFactors out;
  out.options = options;
  for (std::int32_t i = 0; i < n; ++i) {
    out.stats.pairs_tested += tested[i];
    out.stats.rays += rays[i];
    out.stats.pairs_unverified += unverified[i];
    out.stats.pairs_short_of_target += short_of[i];
    out.stats.unverified_exchange += unverified_g[i];
  }
  out.stats.pairs_culled = range_pairs - out.stats.pairs_tested;
  upper.finish(out.F, out.stderr_F);
  std::vector<double> area(n);
  for (std::int32_t i = 0; i < n; ++i) area[i] = geom[i].area;
  mirror_upper(out.F, options.run.with_stderr ? &out.stderr_F : nullptr, area);
  out.stats.seconds = timer.seconds();
  return out;
}

}  // namespace ff

namespace {

// Bytes of one CSR entry: a value and a column index of the storage index type.
constexpr double kCsrEntry = sizeof(double) + sizeof(SparseF::StorageIndex);

// Peak of compute_pairwise for n patches, all n(n-1)/2 pairs exchanging energy (the bound:
// a closed scene reaches it): the CSR F (16 bytes per entry, both triangles), the same again
// for standard errors, and the staging of one block of rows (a 24-byte RowEntry per pair of
// the block, about 1/kBlocks of the pairs) with its pairs' slots (a PairEstimate and a flag).
double pairwise_peak_bytes(std::int64_t patches, const FormFactorOptions& o) {
  const double n = static_cast<double>(patches), pairs = n * (n - 1.0) / 2.0;
  const double csr = 2.0 * 16.0 * (o.run.with_stderr ? 2.0 : 1.0);
  const double staging = (24.0 + sizeof(ff::PairEstimate) + 1.0) * 2.0 /
                         static_cast<double>(ff::kBlocks);  // 2 blocks' worth
  return pairs * (csr + staging);
}

// Peak of compute_hemicube: a row holds at most one entry per hemicube pixel (res^2 on the
// top face, 4 x res x ceil(res/2) on the sides) and at most n - 1; rows are kept as 16-byte
// entries until the CSR F (12 bytes per entry) is filled; averaging (reciprocity.cpp) is in
// place, but F has no room for the union (up to 2 entries per entry), so its one
// reallocation holds the old and the new storage: 2 more CSR entries per entry.
double hemicube_peak_bytes(std::int64_t patches, const FormFactorOptions& o) {
  const double n = static_cast<double>(patches), res = o.hemicube.resolution;
  const double pixels = res * res + 4.0 * res * std::ceil(res / 2.0);
  const double entries = n * std::min(n - 1.0, pixels);
  return entries * (16.0 + 12.0 + (o.reciprocity == "average" ? 2.0 * kCsrEntry : 0.0));
}

// Peak of compute_gather: rows have at most min(K, n - 1) entries; the CSR is written in
// place (assembly.hpp) and averaging adds the mirrors there, so resident memory is the final
// pattern, at most twice the rows' entries (and n(n - 1)); standard errors double it. Plus
// the staging of one block of rows (24-byte entries) and per thread a dense accumulator of
// n doubles and K hits (16 bytes).
double gather_peak_bytes(std::int64_t patches, const FormFactorOptions& o) {
  const double n = static_cast<double>(patches);
  const double row = std::min(n - 1.0, static_cast<double>(o.gather.rays));
  const double entries =
      std::min(n * (n - 1.0), (o.reciprocity == "average" ? 2.0 : 1.0) * n * row);
  const double staging = std::min(n, static_cast<double>(ff::kGatherBlockRows)) * row * 24.0;
  const double per_thread = 8.0 * n + 16.0 * o.gather.rays;
  return entries * kCsrEntry * (o.run.with_stderr ? 2.0 : 1.0) + staging +
         static_cast<double>(resolve_threads(o.run.threads)) * per_thread;
}

// The largest value of the int members the parameters of the first estimators live in (what
// a settings text may hold).
constexpr double kIntMax = std::numeric_limits<std::int32_t>::max();

// The parameters of the first estimators: each lives in its block of FormFactorOptions (the
// kernels read it by name) and is stored in every settings text, in the place it has had
// since the first files.
template <auto Block, auto Member>
double get_int(const FormFactorOptions& o) {
  return (o.*Block).*Member;
}
template <auto Block, auto Member>
void set_int(FormFactorOptions& o, double v) {
  (o.*Block).*Member = static_cast<int>(v);
}
// `p` stored as the int member Block::Member, in every text after `after`.
template <auto Block, auto Member>
EstimatorParam first_count(EstimatorParam p, const char* after) {
  p.stored_always = true;
  p.after = after;
  p.stored_min = 1;
  p.stored_max = kIntMax;
  p.get = &get_int<Block, Member>;
  p.set = &set_int<Block, Member>;
  return p;
}

using O = FormFactorOptions;

EstimatorParam samples_param() {
  EstimatorParam p = first_count<&O::pair, &PairEstimatorParams::samples>(
      integer_param("--samples", "samples", 1, kMaxPairSamples, PairEstimatorParams{}.samples,
                    "Sample pairs (rays) per patch pair (pair estimators mc, hybrid)"),
      "estimator_requested");
  p.required = true;
  return p;
}

// Read by compute_pairwise for mc and hybrid (estimate_to_target); 0 = off.
EstimatorParam target_stderr_param() {
  EstimatorParam p = real_param(
      "--target-stderr", "target_stderr", 0.0, 1.0, 0.0,
      "Sample each pair (from --samples, 4x at a time) until the standard error of both its "
      "factors is at most this (0: off; pair estimators mc, hybrid)");
  return p;
}

EstimatorParam rays_param() {
  EstimatorParam p = first_count<&O::gather, &GatherParams::rays>(
      integer_param("--rays", "rays", 1, 1 << 24, GatherParams{}.rays,
                    "Rays per patch (estimator gather)"),
      "samples");
  p.report = "rays_per_patch";  // "rays" in reports is the count traced
  return p;
}

EstimatorParam hemicube_resolution_param() {
  EstimatorParam p = first_count<&O::hemicube, &HemicubeParams::resolution>(
      integer_param("--hemicube-res", "hemicube_resolution", 4, 8192, HemicubeParams{}.resolution,
                    "Hemicube top-face resolution (estimator hemicube)"),
      "threshold");
  p.key = "hemicube_res";
  return p;
}

EstimatorParam tol_param() {
  EstimatorParam p = real_param("--ff-tol", "tol", 1e-15, 1.0, AnalyticParams{}.tol,
                                "Absolute error target of every form factor (estimator analytic)");
  p.alias = "--tol";  // formfactors has no solver tolerance
  p.after = "hemicube_res";
  p.get = [](const FormFactorOptions& o) { return o.analytic.tol; };
  p.set = [](FormFactorOptions& o, double v) { o.analytic.tol = v; };
  return p;
}

FormFactors run_hybrid(const PatchMesh& m, const FormFactorOptions& o, const Bvh* b) {
  return ff::compute_pairwise(m, o, *b, ff::estimate_hybrid);
}
FormFactors run_mc(const PatchMesh& m, const FormFactorOptions& o, const Bvh* b) {
  return ff::compute_pairwise(m, o, *b, ff::estimate_mc);
}
FormFactors run_hemicube(const PatchMesh& m, const FormFactorOptions& o, const Bvh*) {
  return ff::compute_hemicube(m, o);  // rasterises: no rays
}
FormFactors run_gather(const PatchMesh& m, const FormFactorOptions& o, const Bvh* b) {
  return ff::compute_gather(m, o, *b);
}
FormFactors run_analytic(const PatchMesh& m, const FormFactorOptions& o, const Bvh* b) {
  return ff::compute_pairwise(m, o, *b, ff::estimate_analytic);
}

// The registry: one row per estimator (FormFactorEstimator: name, pairwise, traces_rays,
// uses_bvh, count_option, auto_average, compute, peak_bytes, params).
std::vector<FormFactorEstimator> make_registry() {
  // clang-format off
  return {
      {"hybrid", true, true, true, "samples", false, run_hybrid, pairwise_peak_bytes,
       {samples_param(), target_stderr_param()}},
      {"mc", true, true, true, "samples", false, run_mc, pairwise_peak_bytes,
       {samples_param(), target_stderr_param()}},
      {"hemicube", false, false, false, "", false, run_hemicube, hemicube_peak_bytes,
       {hemicube_resolution_param()}},
      {"gather", false, true, true, "rays", true, run_gather, gather_peak_bytes, {rays_param()}},
      {"analytic", true, false, true, "tol", false, run_analytic, pairwise_peak_bytes,
       {tol_param()}},
  };
  // clang-format on
}

std::vector<FormFactorEstimator>& registry() {
  static std::vector<FormFactorEstimator> table = make_registry();
  return table;
}

// Set when the parameters were first listed (estimator_params): the registry is then final.
bool& registry_read() {
  static bool read = false;
  return read;
}

// Drops the pairs whose factors are both below the threshold: F_ij and F_ji go together,
// so a reciprocal F stays reciprocal (cg, southwell and the energy balance rely on it).
// Standard errors (same sparsity pattern) follow their entries.
void apply_threshold(FormFactors& ff, double threshold) {
  if (threshold <= 0.0) return;
  const bool with_err = ff.stderr_F.nonZeros() > 0;
  std::vector<char> keep(ff.F.nonZeros());
  for (Eigen::Index i = 0; i < ff.F.rows(); ++i) {
    for (std::int64_t k = ff.F.outerIndexPtr()[i]; k < ff.F.outerIndexPtr()[i + 1]; ++k) {
      const Eigen::Index j = ff.F.innerIndexPtr()[k];
      keep[k] = ff.F.valuePtr()[k] >= threshold || ff.F.coeff(j, i) >= threshold;
    }
  }
  // Mark dropped entries with NaN (never a form factor), then prune them.
  for (std::int64_t k = 0; k < ff.F.nonZeros(); ++k) {
    if (keep[k]) continue;
    ff.F.valuePtr()[k] = std::nan("");
    if (with_err) ff.stderr_F.valuePtr()[k] = std::nan("");
  }
  auto not_nan = [](Eigen::Index, Eigen::Index, double v) { return !std::isnan(v); };
  ff.F.prune(not_nan);
  if (with_err) ff.stderr_F.prune(not_nan);
}

const FormFactorEstimator& find_estimator(const std::string& name) {
  for (const auto& e : form_factor_estimator_table())
    if (name == e.name) return e;
  throw UsageError("unknown form-factor estimator '" + name + "'");
}

}  // namespace

EstimatorParam integer_param(std::string option, std::string keyword, double lo, double hi,
                             double fallback, std::string doc) {
  EstimatorParam p;
  p.option = std::move(option);
  p.keyword = std::move(keyword);
  p.lo = lo;
  p.hi = hi;
  p.fallback = fallback;
  p.doc = std::move(doc);
  return p;
}

EstimatorParam real_param(std::string option, std::string keyword, double lo, double hi,
                          double fallback, std::string doc, bool open_lo) {
  EstimatorParam p =
      integer_param(std::move(option), std::move(keyword), lo, hi, fallback, std::move(doc));
  p.integer = false;
  p.open_lo = open_lo;
  return p;
}

namespace {

// The same declaration (two estimators may share a parameter: one option, one meaning).
bool same_param(const EstimatorParam& a, const EstimatorParam& b) {
  return a.keyword == b.keyword && a.integer == b.integer && a.lo == b.lo && a.hi == b.hi &&
         a.open_lo == b.open_lo && a.fallback == b.fallback && a.doc == b.doc && a.get == b.get &&
         a.set == b.set;
}

}  // namespace

void register_form_factor_estimator(FormFactorEstimator estimator) {
  LAMBERT_CHECK(!registry_read(), "register_form_factor_estimator after the registry was read");
  LAMBERT_CHECK(estimator.compute != nullptr && estimator.peak_bytes != nullptr,
                "estimator '" + estimator.name + "' without compute or peak_bytes");
  for (const FormFactorEstimator& e : registry())
    LAMBERT_CHECK(e.name != estimator.name, "estimator '" + estimator.name + "' registered twice");
  LAMBERT_CHECK(estimator.name != "auto" && !estimator.name.empty(), "bad estimator name");
  registry().push_back(std::move(estimator));
}

const std::vector<FormFactorEstimator>& form_factor_estimator_table() {
  registry_read() = true;
  return registry();
}

const std::vector<DeclaredEstimatorParam>& estimator_params() {
  static const std::vector<DeclaredEstimatorParam> params = [] {
    std::vector<DeclaredEstimatorParam> out;
    for (const FormFactorEstimator& e : form_factor_estimator_table())
      for (const EstimatorParam& p : e.params) {
        auto it = std::find_if(out.begin(), out.end(), [&](const DeclaredEstimatorParam& d) {
          return d.param.option == p.option;
        });
        if (it == out.end()) {
          LAMBERT_CHECK(p.option.rfind("--", 0) == 0 && !p.keyword.empty(),
                        "estimator parameter '" + p.option + "' without option or keyword");
          out.push_back({p, {}});
          it = out.end() - 1;
        }
        LAMBERT_CHECK(same_param(it->param, p),
                      "estimator parameter " + p.option + " declared two ways");
        it->estimators.push_back(e.name);
      }
    return out;
  }();
  return params;
}

const DeclaredEstimatorParam* find_estimator_param(const std::string& option) {
  for (const DeclaredEstimatorParam& d : estimator_params())
    if (d.param.option == option) return &d;
  return nullptr;
}

namespace {

const EstimatorParam& declared_param(const std::string& option) {
  const DeclaredEstimatorParam* d = find_estimator_param(option);
  LAMBERT_CHECK(d != nullptr, "no estimator declares the parameter " + option);
  return d->param;
}

}  // namespace

double estimator_param(const FormFactorOptions& options, const std::string& option) {
  const EstimatorParam& p = declared_param(option);
  if (p.get) return p.get(options);
  const auto it = options.params.find(option);
  return it == options.params.end() ? p.fallback : it->second;
}

void set_estimator_param(FormFactorOptions& options, const std::string& option, double value) {
  const EstimatorParam& p = declared_param(option);
  if (p.integer) value = std::round(value);
  if (p.set)
    p.set(options, value);
  else
    options.params[option] = value;
}

std::vector<std::string> form_factor_estimators() {
  std::vector<std::string> names;
  for (const auto& e : form_factor_estimator_table()) names.emplace_back(e.name);
  return names;
}

std::vector<std::string> form_factor_estimator_choices() {
  std::vector<std::string> names = form_factor_estimators();
  names.emplace_back("auto");
  return names;
}

std::string auto_estimator(std::int64_t patches, bool tol_given) {
  if (tol_given && patches <= kAutoAnalyticMaxPatches) return "analytic";
  return patches >= kAutoGatherPatches ? "gather" : "hybrid";
}

std::vector<std::int32_t> balanced_pair_rows(std::int32_t n, int parts) {
  LAMBERT_CHECK(parts >= 1 && n >= 0, "balanced_pair_rows: bad arguments");
  // Pairs of rows [0, i): P(i) = i (n - 1) - i (i - 1) / 2, increasing in i. Part r starts at
  // the first row i with P(i) >= r P(n) / parts (a binary search in exact integers).
  const std::int64_t m = n;
  auto pairs_before = [m](std::int64_t i) { return i * (m - 1) - i * (i - 1) / 2; };
  const std::int64_t total = pairs_before(m);
  std::vector<std::int32_t> first(static_cast<size_t>(parts) + 1, n);
  first[0] = 0;
  for (int r = 1; r < parts; ++r) {
    const std::int64_t target = (total / parts) * r + (total % parts) * r / parts;
    std::int64_t lo = 0, hi = m;
    while (lo < hi) {
      const std::int64_t mid = (lo + hi) / 2;
      if (pairs_before(mid) >= target)
        hi = mid;
      else
        lo = mid + 1;
    }
    first[r] = static_cast<std::int32_t>(std::max<std::int64_t>(lo, first[r - 1]));
  }
  return first;
}

bool is_pair_estimator(const std::string& estimator) { return find_estimator(estimator).pairwise; }

std::string estimator_count_option(const std::string& estimator) {
  return find_estimator(estimator).count_option;
}

FormFactorOptions resolve_form_factor_options(const FormFactorOptions& options,
                                              std::int64_t patches) {
  FormFactorOptions o = options;
  if (o.estimator == "auto") {
    o.estimator = auto_estimator(patches, o.analytic.tol_given);
    o.estimator_requested = "auto";
  }
  const FormFactorEstimator& e = find_estimator(o.estimator);
  if (o.reciprocity == "auto") o.reciprocity = e.auto_average ? "average" : "none";
  if (o.reciprocity != "none" && o.reciprocity != "average")
    throw UsageError("unknown reciprocity mode '" + o.reciprocity + "' (none, average, auto)");
  return o;
}

double form_factor_peak_bytes(std::int64_t patches, const FormFactorOptions& options) {
  const FormFactorOptions o = resolve_form_factor_options(options, patches);
  return find_estimator(o.estimator).peak_bytes(patches, o);
}

FormFactors compute_form_factors(const PatchMesh& mesh, const FormFactorOptions& options,
                                 const Bvh* bvh) {
  if (options.pair.samples < 1) throw UsageError("--samples must be at least 1");
  if (options.gather.rays < 1) throw UsageError("--rays must be at least 1");
  if (!(options.analytic.tol > 0.0) || !std::isfinite(options.analytic.tol))
    throw UsageError("--ff-tol must be a positive number");
  // Not `threshold < 0`: NaN passes that and drops nothing (issue 33: Python took nan).
  if (!(options.threshold >= 0.0 && options.threshold <= 1.0))
    throw UsageError("--threshold must be a number in [0, 1]");
  if (options.hemicube.resolution < 4 || options.hemicube.resolution > 8192)
    throw UsageError("--hemicube-res must be in [4, 8192]");
  if (mesh.patches.empty()) throw UsageError("the scene has no patches");
  const FormFactorOptions o = resolve_form_factor_options(options, mesh.size());
  const FormFactorEstimator& e = find_estimator(o.estimator);
  for (const EstimatorParam& p : e.params) {
    if (p.get) continue;  // the first estimators' parameters: checked above
    const double v = estimator_param(o, p.option);
    const bool above = p.open_lo ? v > p.lo : v >= p.lo;
    if (!(std::isfinite(v) && above && v <= p.hi && (!p.integer || v == std::floor(v)))) {
      char range[96];
      std::snprintf(range, sizeof range, "%s%g, %g]", p.open_lo ? "(" : "[", p.lo, p.hi);
      throw UsageError(p.option + " must be " + (p.integer ? "an integer" : "a number") + " in " +
                       range);
    }
  }
  // Standard errors come from the spread of independent replicates (replicates.hpp),
  // which needs at least two of them, and Student's t with so few is wide: ask for four.
  const std::string count = e.count_option;
  if (count == "samples" && estimator_param(o, "--target-stderr") > 0.0 && o.pair.samples < 4)
    throw UsageError(
        "--target-stderr needs --samples of at least 4 (standard errors come from independent "
        "replicates of the samples)");
  if (e.traces_rays && o.run.with_stderr && (count == "rays" ? o.gather.rays : o.pair.samples) < 4)
    throw UsageError("--stderr needs --" + count +
                     " of at least 4 (standard errors come from "
                     "independent replicates of the " +
                     count + ")");
  const bool specular = mesh.has_specular() && o.specular.depth > 0;
  if (specular && !e.traces_rays)
    throw UsageError("--estimator " + o.estimator +
                     " does not follow rays through mirrors and "
                     "glass: use mc, hybrid or gather for this scene, or --specular-depth 0 "
                     "(specular surfaces then only receive and block)");
  if (specular) ff::check_grey_specular(mesh);
  std::unique_ptr<Bvh> own;
  if (!bvh && e.uses_bvh) {
    own = std::make_unique<Bvh>(mesh, o.run.threads);
    bvh = own.get();
  }
  const bool ranged = o.subset.row_end > o.subset.row_begin;
  if (ranged) {
    if (o.subset.row_begin < 0 || o.subset.row_end > mesh.size())
      throw UsageError("row range [" + std::to_string(o.subset.row_begin) + ", " +
                       std::to_string(o.subset.row_end) + ") outside the mesh");
    if (!e.pairwise)
      throw UsageError("--estimator " + o.estimator +
                       " computes whole rows and its reciprocity "
                       "needs whole columns: distributed form factors take mc, hybrid or analytic");
    if (o.reciprocity == "average")
      throw UsageError(
          "--reciprocity average needs whole columns: distributed form factors "
          "take the pair estimators' own reciprocity (--reciprocity none)");
    if (specular)
      throw UsageError(
          "specular paths cross every row: distributed form factors need "
          "--specular-depth 0 on a scene with mirrors or glass");
    if (!o.subset.only.empty()) throw UsageError("a row range does not combine with an update");
  }
  FormFactors out = e.compute(mesh, o, bvh);
  out.options = o;
  if (ranged) {
    // Each pair's two entries are on this side, so the pair threshold applies as a whole.
    apply_threshold(out, o.threshold);
    return out;
  }
  if (!o.subset.only.empty()) {
    LAMBERT_CHECK(o.subset.only.size() == mesh.patches.size(), "row flags do not match the mesh");
    return out;  // partial: update_form_factors completes it
  }
  if (o.reciprocity == "average") {
    Timer timer;
    std::vector<double> areas(mesh.patches.size());
    for (size_t i = 0; i < areas.size(); ++i) areas[i] = mesh.patches[i].area;
    out.F.makeCompressed();
    const std::vector<char> kept = o.estimator == "gather"
                                       ? ff::gather_direct_patches(mesh, o.gather.rays)
                                       : std::vector<char>{};
    ff::average_reciprocal(out.F, o.run.with_stderr ? &out.stderr_F : nullptr, areas, out.stats,
                           o.run.threads, &kept);
    if (o.estimator == "gather") {  // its pairs: those connected either way = the pattern's
      const std::int64_t n = mesh.size();
      out.stats.pairs_tested = out.F.nonZeros() / 2;
      out.stats.pairs_culled = n * (n - 1) / 2 - out.stats.pairs_tested;
    }
    out.stats.reciprocity_seconds = timer.seconds();
    out.stats.seconds += out.stats.reciprocity_seconds;
  }
  // The specular paths after the direct part's averaging, whose row-sum cap assumes rows
  // of at most 1 (extended rows may exceed it): S is reciprocal by its own averaging.
  if (specular) {
    ff::add_specular_transport(mesh, o, *bvh, out);
    out.options.contents.extended = true;
  }
  apply_threshold(out, o.threshold);
  return out;
}

FormFactors update_form_factors(const PatchMesh& mesh, const std::vector<std::int32_t>& origin,
                                const SparseF& old_F, const FormFactorOptions& options,
                                const Bvh* bvh) {
  // Specular paths connect patches far apart through mirrors: recomputed whole.
  if (mesh.has_specular() && options.specular.depth > 0)
    return compute_form_factors(mesh, options, bvh);
  const std::int32_t n = mesh.size();
  LAMBERT_CHECK(static_cast<std::int32_t>(origin.size()) == n, "origin map does not match the mesh");
  FormFactorOptions o = options;
  o.run.with_stderr = false;
  o.subset.only.assign(n, 0);
  for (std::int32_t i = 0; i < n; ++i) o.subset.only[i] = origin[i] < 0;
  FormFactors part = compute_form_factors(mesh, o, bvh);
  const bool pairwise = estimator_count_option(part.options.estimator) == "samples";
  // Both sides of a pair with a new patch: G from row i is A_i F_ij where row i was
  // estimated (a pair estimator's every row; a row estimator's new rows).
  auto estimated = [&](std::int32_t i) { return pairwise || origin[i] < 0; };
  std::vector<double> area(n);
  for (std::int32_t i = 0; i < n; ++i) area[i] = mesh.patches[i].area;
  std::vector<Eigen::Triplet<double, std::int64_t>> entries;
  std::vector<std::int32_t> new_of_old(old_F.rows(), -1);
  for (std::int32_t i = 0; i < n; ++i)
    if (origin[i] >= 0) new_of_old[origin[i]] = i;
  for (std::int32_t i = 0; i < n; ++i) {
    if (origin[i] < 0) continue;
    for (SparseF::InnerIterator it(old_F, origin[i]); it; ++it) {
      const std::int32_t j = new_of_old[it.col()];
      if (j >= 0) entries.emplace_back(i, j, it.value());
    }
  }
  // Pairs with a new patch: each side's G, keyed by the unordered pair, sorted so that the
  // (at most two) sides of a pair are adjacent, then averaged (16 bytes per side, O(m log m)).
  struct Side {
    std::int32_t i, j;  // i < j
    double G;
  };
  std::vector<Side> sides;
  for (std::int32_t i = 0; i < n; ++i) {
    if (!estimated(i)) continue;
    for (SparseF::InnerIterator it(part.F, i); it; ++it) {
      const auto j = static_cast<std::int32_t>(it.col());
      if (origin[i] >= 0 && origin[j] >= 0) continue;
      sides.push_back({std::min(i, j), std::max(i, j), area[i] * it.value()});
    }
  }
  std::stable_sort(sides.begin(), sides.end(), [](const Side& a, const Side& b) {
    return a.i != b.i ? a.i < b.i : a.j < b.j;
  });
  for (size_t k = 0; k < sides.size();) {
    const std::int32_t i = sides[k].i, j = sides[k].j;
    double sum = 0.0;
    int count = 0;
    for (; k < sides.size() && sides[k].i == i && sides[k].j == j; ++k, ++count) sum += sides[k].G;
    // Sides estimated but without an entry estimated G = 0: they count in the mean.
    const int estimated_sides = (estimated(i) ? 1 : 0) + (estimated(j) ? 1 : 0);
    const double G = sum / std::max(estimated_sides, count);
    if (!(G > 0.0)) continue;
    entries.emplace_back(i, j, G / area[i]);
    entries.emplace_back(j, i, G / area[j]);
  }
  FormFactors out;
  out.options = part.options;
  out.options.subset.only.clear();
  out.stats = part.stats;
  out.F.resize(n, n);
  out.F.setFromTriplets(entries.begin(), entries.end());
  out.F.makeCompressed();
  return out;
}

}  // namespace lambert
