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
// Memory per task: K hits (16 bytes); rows are kept as (j, F) until assembled.
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
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/replicates.hpp"

namespace lambert::ff {
namespace {

struct Hit {
  std::int32_t j;
  std::int32_t rep;
  double w;
};

struct RowEntry {
  std::int32_t j;
  double f;
  double err;
};

// An orthonormal frame (t, b, n) for unit n (Duff et al. 2017, branchless).
void frame(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

// Traces row i's K rays into `hits` (cleared first).
void trace_row(const std::vector<PatchGeom>& geom, const Bvh& bvh, std::int32_t i, int K,
               std::uint64_t seed, double offset, std::vector<Hit>& hits) {
  const PatchGeom& g = geom[i];
  Eigen::Vector3d t, b;
  frame(g.normal, t, b);
  hits.clear();
  const int R = replicate_count(K);
  for (int rep = 0; rep < R; ++rep) {
    const Kronecker4 seq(
        hash_keys(seed, static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(rep)));
    const int k = replicate_size(K, rep);
    for (int s = 0; s < k; ++s) {
      double jac;
      const Eigen::Vector3d x = sample_patch(g, seq.get(s, 0), seq.get(s, 1), jac);
      const double r = std::sqrt(seq.get(s, 2)), phi = 2.0 * M_PI * seq.get(s, 3);
      const double z = std::sqrt(std::max(0.0, 1.0 - seq.get(s, 2)));
      const Eigen::Vector3d dir = r * std::cos(phi) * t + r * std::sin(phi) * b + z * g.normal;
      const Eigen::Vector3d origin = x + offset * g.normal;
      const RayHit hit = bvh.intersect(origin.cast<float>(), dir.cast<float>());
      if (hit.patch < 0 || hit.patch == i) continue;
      if (dir.dot(geom[hit.patch].normal) >= 0.0) continue;  // the back of j: absorbed
      hits.push_back({hit.patch, rep, jac / g.area});
    }
  }
}

// Row i's entries from its hits: F_ij = Σ w / K, the error from the replicate estimates
// (Σ_{hits in r} w) / k_r.
void row_from_hits(std::vector<Hit>& hits, int K, bool with_err, std::vector<RowEntry>& row) {
  std::stable_sort(hits.begin(), hits.end(),
                   [](const Hit& a, const Hit& b) { return a.j < b.j; });
  const int R = replicate_count(K);
  row.clear();
  for (size_t h = 0; h < hits.size();) {
    const std::int32_t j = hits[h].j;
    double per_rep[kReplicates] = {};
    double sum = 0.0;
    for (; h < hits.size() && hits[h].j == j; ++h) {
      per_rep[hits[h].rep] += hits[h].w;
      sum += hits[h].w;
    }
    double err = 0.0;
    if (with_err) {
      for (int r = 0; r < R; ++r) per_rep[r] /= replicate_size(K, r);
      err = std::sqrt(replicate_variance(per_rep, R));
    }
    row.push_back({j, sum / K, err});
  }
}

}  // namespace

FormFactors compute_gather(const PatchMesh& mesh, const FormFactorOptions& options,
                           const Bvh& bvh) {
  if (options.rays < 1) throw UsageError("--rays must be at least 1");
  Timer timer;
  const std::int32_t n = mesh.size();
  const int K = options.rays;
  const std::vector<PatchGeom> geom = patch_geometry(mesh);
  const double offset = kRayOffset * mesh.scale;

  std::vector<std::vector<RowEntry>> rows(n);
  Progress progress("gather", options.progress ? n : 0, "rays");
  // Chunks of 16 rows: a row is K rays (~0.1 ms at K = 1024), so a chunk is a few ms,
  // large enough to amortise the hit buffer, small enough to balance.
  parallel_for(n, 16, options.threads, [&](std::int64_t begin, std::int64_t end) {
    std::vector<Hit> hits;
    hits.reserve(K);
    for (std::int64_t ii = begin; ii < end; ++ii) {
      const auto i = static_cast<std::int32_t>(ii);
      trace_row(geom, bvh, i, K, options.seed, offset, hits);
      row_from_hits(hits, K, options.with_stderr, rows[i]);
      rows[i].shrink_to_fit();
      progress.advance(1, K);
    }
  });
  progress.finish();

  FormFactors out;
  out.options = options;
  std::int64_t nnz = 0;
  for (const auto& r : rows) nnz += static_cast<std::int64_t>(r.size());
  LAMBERT_CHECK(nnz <= std::numeric_limits<SparseF::StorageIndex>::max(),
                "too many form factors for the sparse index type");
  using Index = SparseF::StorageIndex;
  SparseF F(n, n), S;
  F.resizeNonZeros(nnz);
  if (options.with_stderr) {
    S.resize(n, n);
    S.resizeNonZeros(nnz);
  }
  std::int64_t at = 0;
  for (std::int32_t i = 0; i < n; ++i) {
    F.outerIndexPtr()[i] = static_cast<Index>(at);
    if (options.with_stderr) S.outerIndexPtr()[i] = static_cast<Index>(at);
    for (const RowEntry& e : rows[i]) {
      F.innerIndexPtr()[at] = e.j;
      F.valuePtr()[at] = e.f;
      if (options.with_stderr) {
        S.innerIndexPtr()[at] = e.j;
        S.valuePtr()[at] = e.err;
      }
      ++at;
    }
    std::vector<RowEntry>().swap(rows[i]);  // release memory as we go
  }
  F.outerIndexPtr()[n] = static_cast<Index>(at);
  if (options.with_stderr) S.outerIndexPtr()[n] = static_cast<Index>(at);

  // Pairs connected either way: the union of F's and F^T's patterns, each pair twice.
  const SparseF Ft = F.transpose();
  const SparseF U = F + Ft;
  out.stats.pairs_tested = U.nonZeros() / 2;
  out.stats.pairs_culled = static_cast<std::int64_t>(n) * (n - 1) / 2 - out.stats.pairs_tested;
  out.stats.rays = static_cast<std::int64_t>(n) * K;
  out.F.swap(F);  // swap: Eigen 3.4 sparse matrices have no move (std::move copies)
  if (options.with_stderr) out.stderr_F.swap(S);
  out.stats.seconds = timer.seconds();
  return out;
}

}  // namespace lambert::ff
