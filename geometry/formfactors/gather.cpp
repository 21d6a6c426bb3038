// Estimator "gather": cosine-distributed rays from every patch. See gather.hpp for the
// estimate.
//
// Per row i, replicate r (R = min(K, 16), replicates.hpp), point s of that replicate's
// randomly shifted 4-D Kronecker lattice (u0, u1, u2, u3) (shift from hash_keys(seed, i, r)):
//   x = sample_patch(i, u0, u1), lifted by kRayOffset · scale along n_i;
//   ω = Malley's method: the uniform point (√u2 cos 2πu3, √u2 sin 2πu3) on the unit disk
//       lifted to the hemisphere, z = √(1 − u2): density cosθ / π;
//   one closest-hit ray; a hit on the front of j ≠ i (ω · n_j < 0) adds w = J / A_i.
// The lattice stratifies (x, ω) jointly, so the error falls faster than 1/√K for smooth
// rows; the replicates keep the error estimate honest (the multinomial sqrt(p (1 − p) / K)
// would overstate a lattice's error, and would be wrong for tapered quads' weights).
// An entry no ray hit is absent, with no standard error: its factor is below ~1/K (a
// patch subtending < 1/K of the cosine-weighted hemisphere is missed with probability
// (1 − F_ij)^K); the estimate is still unbiased (0 is the most likely value of a small one).
// Memory per thread: K hits (16 bytes) and a dense accumulator of N doubles; rows are
// staged one block at a time (kGatherBlockRows) and appended to the reserved CSR.
// Thread safety: rows only write their own slots.

#include "geometry/formfactors/gather.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/assembly.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/mirror.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/replicates.hpp"

namespace lambert::ff {
namespace {


struct Hit {
  std::int32_t j;
  std::int32_t rep;
  double w;
};

// Traces row i's K rays into `hits` (cleared first).
// `normals`: the patches' normals packed (the front test reads one per hit, at random:
// 24 bytes apart instead of a whole PatchGeom).
void trace_row(const std::vector<PatchGeom>& geom, const std::vector<Eigen::Vector3d>& normals,
               const Bvh& bvh, std::int32_t i, int K, std::uint64_t seed, double offset,
               std::vector<Hit>& hits) {
  const PatchGeom& g = geom[i];
  Eigen::Vector3d t, b;
  orthonormal_frame(g.normal, t, b);
  hits.clear();
  // The row's rays go Bvh::kPacket at a time (one patch's origins: Embree's packets trace
  // them ~1.2x faster than one by one, with the same hits); hits are kept in ray order.
  Eigen::Vector3f origin[Bvh::kPacket], direction[Bvh::kPacket];
  Eigen::Vector3d dir[Bvh::kPacket];
  int rep_of[Bvh::kPacket];
  double weight[Bvh::kPacket];
  RayHit hit[Bvh::kPacket];
  int pending = 0;
  auto flush = [&] {
    bvh.intersect_packet(origin, direction, pending, hit);
    for (int k = 0; k < pending; ++k) {
      if (hit[k].patch < 0 || hit[k].patch == i) continue;
      if (dir[k].dot(normals[hit[k].patch]) >= 0.0) continue;  // the back of j: absorbed
      hits.push_back({hit[k].patch, rep_of[k], weight[k]});
    }
    pending = 0;
  };
  const int R = replicate_count(K);
  for (int rep = 0; rep < R; ++rep) {
    const Kronecker4 seq(
        hash_keys(seed, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(rep)));
    const int k = replicate_size(K, rep);
    for (int s = 0; s < k; ++s) {
      double jac;
      const Eigen::Vector3d x = sample_patch(g, seq.get(s, 0), seq.get(s, 1), jac);
      dir[pending] = cosine_direction(g.normal, t, b, seq.get(s, 2), seq.get(s, 3));
      origin[pending] = (x + end_lift(g, offset) * g.normal).cast<float>();
      direction[pending] = dir[pending].cast<float>();
      rep_of[pending] = rep;
      weight[pending] = jac / g.area;
      if (++pending == Bvh::kPacket) flush();
    }
  }
  flush();
}

// A sort of t touched columns costs ~t log t comparisons, a scan of the accumulator one
// (vectorisable) test per patch: scan when t >= n / kScanPerTouched.
constexpr std::int64_t kScanPerTouched = 32;

// Row i's entries from its hits: F_ij = Σ w / K (summed in hit order), and with `with_err`
// the error from the replicate estimates (Σ_{hits in r} w) / k_r. Without errors the sums
// go through a dense accumulator over the patches (`acc`, all zero on entry and on return;
// O(hits + min(distinct log distinct, patches))); with errors the hits are sorted by patch
// (stable, so each sum is in the same order and F is bitwise the same either way).
void row_from_hits(std::vector<Hit>& hits, int K, bool with_err, std::vector<double>& acc,
                   std::vector<std::int32_t>& touched, std::vector<RowEntry>& row) {
  row.clear();
  if (!with_err) {
    touched.clear();
    for (const Hit& h : hits) {
      if (acc[h.j] == 0.0) touched.push_back(h.j);
      acc[h.j] += h.w;
    }
    const auto n = static_cast<std::int32_t>(acc.size());
    if (static_cast<std::int64_t>(touched.size()) * kScanPerTouched >= n) {
      // Many patches touched (a few thousand patches, K ~ 1024): one pass over the
      // accumulator in column order costs less than sorting them (the same row).
      for (std::int32_t j = 0; j < n; ++j)
        if (acc[j] != 0.0) {
          if (acc[j] > 0.0) row.push_back({j, acc[j] / K, 0.0});
          acc[j] = 0.0;
        }
      return;
    }
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());  // w = 0 hits
    for (const std::int32_t j : touched) {
      if (acc[j] > 0.0) row.push_back({j, acc[j] / K, 0.0});
      acc[j] = 0.0;
    }
    return;
  }
  std::stable_sort(hits.begin(), hits.end(),
                   [](const Hit& a, const Hit& b) { return a.j < b.j; });
  const int R = replicate_count(K);
  for (size_t h = 0; h < hits.size();) {
    const std::int32_t j = hits[h].j;
    double per_rep[kReplicates] = {};
    double sum = 0.0;
    for (; h < hits.size() && hits[h].j == j; ++h) {
      per_rep[hits[h].rep] += hits[h].w;
      sum += hits[h].w;
    }
    for (int r = 0; r < R; ++r) per_rep[r] /= replicate_size(K, r);
    row.push_back({j, sum / K, std::sqrt(replicate_variance(per_rep, R))});
  }
}

// The emitter pairs (direct light) by the hybrid kernel, G_ij for every pair with an
// emitter: direct[i] holds (j, G_ij, var) for the emitters j of row i (for an emitter i,
// those j > i), rows computed in parallel, each pair once with its own stream
// hash_keys(seed, i, j) (bitwise the same for any thread count). With `only`, the pairs
// with a flagged patch. Returns the rays traced.
std::int64_t emitter_pairs(const std::vector<PatchGeom>& geom, const Bvh& bvh,
                           const std::vector<std::int32_t>& emitters,
                           const std::vector<char>& is_emitter, const FormFactorOptions& options,
                           double offset, double plane_eps,
                           std::vector<std::vector<RowEntry>>& direct) {
  const auto n = static_cast<std::int32_t>(geom.size());
  const PairContext ctx{geom, bvh, kGatherDirectSamples, options.run.seed, offset};
  const std::vector<char>& only = options.subset.only;
  direct.assign(n, {});
  std::vector<std::int64_t> rays(n, 0);
  parallel_for(n, 64, options.run.threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t r = begin; r < end; ++r) {
      const auto i = static_cast<std::int32_t>(r);
      for (const std::int32_t j : emitters) {
        if (j == i || (is_emitter[i] && j < i)) continue;
        if (!only.empty() && !only[i] && !only[j]) continue;
        if (!can_exchange(geom[i], geom[j], plane_eps)) continue;
        const PairEstimate e = estimate_hybrid(ctx, std::min(i, j), std::max(i, j));
        rays[i] += e.rays;
        if (e.G > 0.0) direct[i].push_back({j, e.G, e.var});
      }
    }
  });
  std::int64_t total = 0;
  for (const std::int64_t k : rays) total += k;
  return total;
}

// Row i with the emitter pairs: an emitter's row is its pairs alone (G / A_i, errors
// sqrt(var) / A_i); another row traces its K rays, drops the hits on emitters and scales
// the rest by s = (1 - h_i) / (1 - f_E), h_i = Σ_emitters G_ij / A_i the emitters' exact
// share of its cosine-weighted hemisphere and f_E the rays' share that hit them: the rays
// that miss the emitters sample the rest of the hemisphere, whose measure is 1 - h_i (a
// ratio estimator: consistent, and a closed scene's row still sums to 1 exactly).
void direct_row(const std::vector<PatchGeom>& geom, const std::vector<Eigen::Vector3d>& normals,
                const Bvh& bvh, std::int32_t i, int K, const FormFactorOptions& options,
                double offset, const std::vector<char>& is_emitter,
                const std::vector<RowEntry>& pairs, const std::vector<RowEntry>& column_pairs,
                std::vector<Hit>& hits, std::vector<double>& acc,
                std::vector<std::int32_t>& touched, std::vector<RowEntry>& row) {
  const double area = geom[i].area;
  auto entry = [&](const RowEntry& p) {
    return RowEntry{p.col, p.value / area, std::sqrt(std::max(0.0, p.err)) / area};
  };
  row.clear();
  if (is_emitter[i]) {
    for (const RowEntry& p : column_pairs) row.push_back(entry(p));
    for (const RowEntry& p : pairs) row.push_back(entry(p));
  } else {
    trace_row(geom, normals, bvh, i, K, options.run.seed, offset, hits);
    double f_e = 0.0;
    for (const Hit& h : hits)
      if (is_emitter[h.j]) f_e += h.w;
    f_e /= K;
    hits.erase(std::remove_if(hits.begin(), hits.end(),
                              [&](const Hit& h) { return is_emitter[h.j] != 0; }),
               hits.end());
    row_from_hits(hits, K, options.run.with_stderr, acc, touched, row);
    double h_i = 0.0;
    for (const RowEntry& p : pairs) h_i += p.value / area;
    const double s = f_e < 1.0 ? std::max(0.0, 1.0 - h_i) / (1.0 - f_e) : 1.0;
    for (RowEntry& e : row) {
      e.value *= s;
      e.err *= s;
    }
    for (const RowEntry& p : pairs) row.push_back(entry(p));
  }
  std::sort(row.begin(), row.end(),
            [](const RowEntry& a, const RowEntry& b) { return a.col < b.col; });
  if (!options.run.with_stderr)
    for (RowEntry& e : row) e.err = 0.0;
}

// Unordered pairs with an entry on at least one side: every upper entry, plus the lower
// entries whose mirror is absent (found by a MirrorCursor, as the averaging finds them).
std::int64_t connected_pairs(const SparseF& F, int threads) {
  using Index = SparseF::StorageIndex;
  const std::int32_t n = static_cast<std::int32_t>(F.rows());
  const Index* outer = F.outerIndexPtr();
  const Index* col = F.innerIndexPtr();
  std::vector<std::int64_t> per_row(n, 0);
  const std::uint64_t call = MirrorCursor::next_call();
  parallel_for(n, 1024, threads, [&](std::int64_t begin, std::int64_t end) {
    thread_local MirrorCursor mirror;
    mirror.rows(n);
    for (std::int64_t i = begin; i < end; ++i) {
      std::int64_t count = 0;
      for (auto k = outer[i]; k < outer[i + 1]; ++k) {
        const Index j = col[k];
        if (j > i || mirror.find(col, outer, j, static_cast<Index>(i), call) < 0) ++count;
      }
      per_row[i] = count;
    }
  });
  std::int64_t total = 0;
  for (const std::int64_t c : per_row) total += c;
  return total;
}

}  // namespace

std::vector<char> gather_direct_patches(const PatchMesh& mesh, std::int64_t rays) {
  std::vector<char> emitter(mesh.patches.size(), 0);
  std::int64_t count = 0;
  for (size_t i = 0; i < emitter.size(); ++i)
    if (mesh.patches[i].emission.maxCoeff() > 0.0) {
      emitter[i] = 1;
      ++count;
    }
  if (!gather_direct_pairs(count, mesh.size(), rays)) emitter.clear();
  return emitter;
}

FormFactors compute_gather(const PatchMesh& mesh, const FormFactorOptions& options,
                           const Bvh& bvh) {
  if (options.gather.rays < 1) throw UsageError("--rays must be at least 1");
  Timer timer;
  const std::int32_t n = mesh.size();
  const int K = options.gather.rays;
  const std::vector<PatchGeom> geom = patch_geometry(mesh);
  const double offset = kRayOffset * mesh.scale;
  std::vector<Eigen::Vector3d> normals(n);
  for (std::int32_t i = 0; i < n; ++i) normals[i] = geom[i].normal;

  // The direct light: with few emitting patches (gather_direct_pairs), every pair with an
  // emitter is estimated by the hybrid kernel instead of by the rays (gather.hpp).
  std::vector<char> is_emitter = gather_direct_patches(mesh, K);
  const bool direct_pairs = !is_emitter.empty();
  if (!direct_pairs) is_emitter.assign(n, 0);
  std::vector<std::int32_t> emitters;
  for (std::int32_t i = 0; i < n; ++i)
    if (is_emitter[i]) emitters.push_back(i);
  std::vector<std::vector<RowEntry>> direct;        // row i's pairs with an emitter (G, var)
  std::vector<std::vector<RowEntry>> emitter_rows;  // an emitter's pairs with lower rows
  std::int64_t direct_rays = 0;
  if (direct_pairs) {
    direct_rays = emitter_pairs(geom, bvh, emitters, is_emitter, options, offset,
                                kPlaneEps * mesh.scale, direct);
    emitter_rows.resize(n);
    for (std::int32_t i = 0; i < n; ++i)
      for (const RowEntry& e : direct[i]) emitter_rows[e.col].push_back({i, e.value, e.err});
  }
  // Rows have at most min(K, n - 1) entries (and their emitters'); reciprocity averaging may
  // add each entry's mirror, in place, so its room is reserved too (address space: see
  // assembly.hpp).
  const double row_max =
      std::min<double>(K + (direct_pairs ? static_cast<double>(emitters.size()) : 0.0), n - 1.0);
  const double room = std::min(static_cast<double>(n) * (n - 1.0),
                               (options.reciprocity == "average" ? 2.0 : 1.0) * n * row_max);
  CsrAppender csr(n, static_cast<std::int64_t>(room), options.run.with_stderr);
  std::vector<std::vector<RowEntry>> rows(std::min<std::int32_t>(n, kGatherBlockRows));
  Progress progress("gather", options.run.progress ? n : 0, "rays");
  for (std::int32_t block = 0; block < n; block += kGatherBlockRows) {
    const std::int32_t count = std::min(kGatherBlockRows, n - block);
    // Chunks of 16 rows: a row is K rays (~0.1 ms at K = 1024), so a chunk is a few ms,
    // large enough to amortise the buffers, small enough to balance.
    parallel_for(count, 16, options.run.threads, [&](std::int64_t begin, std::int64_t end) {
      // Per thread (threads live for one parallel_for): hits and the dense accumulator.
      thread_local std::vector<Hit> hits;
      thread_local std::vector<double> acc;
      thread_local std::vector<std::int32_t> touched;
      acc.resize(n, 0.0);
      hits.reserve(K);
      for (std::int64_t r = begin; r < end; ++r) {
        const auto i = static_cast<std::int32_t>(block + r);
        if (!options.subset.only.empty() && !options.subset.only[i]) {
          rows[r].clear();
          continue;
        }
        if (!direct_pairs) {
          trace_row(geom, normals, bvh, i, K, options.run.seed, offset, hits);
          row_from_hits(hits, K, options.run.with_stderr, acc, touched, rows[r]);
          progress.advance(1, K);
          continue;
        }
        direct_row(geom, normals, bvh, i, K, options, offset, is_emitter, direct[i],
                   emitter_rows[i], hits, acc, touched, rows[r]);
        progress.advance(1, is_emitter[i] ? 0 : K);
      }
    });
    csr.append_rows(rows.data(), count, options.run.threads);
  }
  progress.finish();

  FormFactors out;
  out.options = options;
  csr.finish(out.F, out.stderr_F);
  // Averaging makes the pattern symmetric, and then the pairs are nnz / 2 for free
  // (compute_form_factors counts them there); only an F left as it is needs the search.
  if (options.reciprocity != "average") {
    out.stats.pairs_tested = connected_pairs(out.F, options.run.threads);
    out.stats.pairs_culled = static_cast<std::int64_t>(n) * (n - 1) / 2 - out.stats.pairs_tested;
  }
  out.stats.rays = static_cast<std::int64_t>(
                       n - (direct_pairs ? static_cast<std::int32_t>(emitters.size()) : 0)) *
                       K +
                   direct_rays;
  out.stats.seconds = timer.seconds();
  return out;
}

}  // namespace lambert::ff
