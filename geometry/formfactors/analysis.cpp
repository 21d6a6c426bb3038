#include "geometry/formfactors/analysis.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/replicates.hpp"
#include "geometry/formfactors/visibility.hpp"

namespace lambert {

FormFactorDiagnostics diagnose(const PatchMesh& mesh, const SparseF& F, int worst) {
  FormFactorDiagnostics d;
  d.n = static_cast<std::int32_t>(F.rows());
  d.nnz = F.nonZeros();
  d.row_sum_histogram.assign(FormFactorDiagnostics::kHistogramBins, 0);
  std::vector<double> sums(d.n, 0.0);
  for (std::int32_t i = 0; i < d.n; ++i) {
    for (SparseF::InnerIterator it(F, i); it; ++it) {
      sums[i] += it.value();
      d.negative += it.value() < 0.0;
      d.above_one += it.value() > 1.0;
      // F is row-major: F_ji by binary search in row j.
      const double aij = mesh.patches[i].area * it.value();
      const double aji = mesh.patches[it.col()].area * F.coeff(it.col(), i);
      const double diff = std::abs(aij - aji);
      d.reciprocity_max = std::max(d.reciprocity_max, diff);
      d.reciprocity_max_relative =
          std::max(d.reciprocity_max_relative, diff / std::max(std::abs(aij), std::abs(aji)));
    }
    const int bin = static_cast<int>(sums[i] / FormFactorDiagnostics::kHistogramMax *
                                     FormFactorDiagnostics::kHistogramBins);
    ++d.row_sum_histogram[std::clamp(bin, 0, FormFactorDiagnostics::kHistogramBins - 1)];
  }
  if (d.n > 0) {
    d.row_sum_min = *std::min_element(sums.begin(), sums.end());
    d.row_sum_max = *std::max_element(sums.begin(), sums.end());
    d.row_sum_mean = std::accumulate(sums.begin(), sums.end(), 0.0) / d.n;
    std::vector<std::int32_t> order(d.n);
    std::iota(order.begin(), order.end(), 0);
    const int k = std::min(worst, static_cast<int>(d.n));
    std::partial_sort(order.begin(), order.begin() + k, order.end(),
                      [&](std::int32_t a, std::int32_t b) { return sums[a] > sums[b]; });
    d.worst_rows.assign(order.begin(), order.begin() + k);
  }
  return d;
}

SurfaceFactors surface_factors(const PatchMesh& mesh, const FormFactors& ff) {
  SurfaceFactors out;
  const auto s = static_cast<Eigen::Index>(mesh.surface_names.size());
  out.surfaces = mesh.surface_names;
  out.areas.assign(s, 0.0);
  out.F = Eigen::MatrixXd::Zero(s, s);
  Eigen::MatrixXd var = Eigen::MatrixXd::Zero(s, s);
  const bool have_err = ff.stderr_F.nonZeros() > 0;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    out.areas[p.surface] += p.area;
    // stderr_F shares F's sparsity pattern: walk both CSR arrays by position.
    for (auto k = ff.F.outerIndexPtr()[i]; k < ff.F.outerIndexPtr()[i + 1]; ++k) {
      const auto h = mesh.patches[ff.F.innerIndexPtr()[k]].surface;
      out.F(p.surface, h) += p.area * ff.F.valuePtr()[k];
      if (have_err) var(p.surface, h) += std::pow(p.area * ff.stderr_F.valuePtr()[k], 2);
    }
  }
  for (Eigen::Index g = 0; g < s; ++g) {
    if (out.areas[g] <= 0.0) continue;
    out.F.row(g) /= out.areas[g];
    var.row(g) /= out.areas[g] * out.areas[g];
  }
  out.stderr_F = var.cwiseSqrt();
  return out;
}

PointFactors point_form_factors(const PatchMesh& mesh, const Eigen::Vector3d& point,
                                const Eigen::Vector3d& normal, const FormFactorOptions& options) {
  if (!point.allFinite() || !(normal.norm() > 0.0) || !normal.allFinite())
    throw UsageError("--point and --normal must be finite and the normal non-zero");
  const Eigen::Vector3d n = normal.normalized();
  const std::vector<ff::PatchGeom> geom = ff::patch_geometry(mesh);
  const Bvh bvh(mesh);
  const double offset = ff::kRayOffset * mesh.scale;
  const std::int32_t np = mesh.size();
  std::vector<double> f(np, 0.0), var(np, 0.0);
  std::vector<std::int64_t> rays(np, 0);
  parallel_for(np, 64, options.threads, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t jj = b; jj < e; ++jj) {
      const auto j = static_cast<std::int32_t>(jj);
      const double unocc = ff::point_to_patch(point, n, geom[j]);
      if (unocc <= 0.0) continue;
      // The shared visible-fraction kernel (visibility.hpp), in replicates for the error.
      const int R = ff::replicate_count(options.samples);
      double replicate[ff::kReplicates];
      int seen = 0, exhausted = 0;
      for (int rep = 0; rep < R; ++rep) {
        const int k = ff::replicate_size(options.samples, rep);
        const int v = ff::count_visible(
            bvh, point, n, geom[j], k,
            hash_keys(options.seed, 0xFFFFFFFFull, hash_keys(j, static_cast<std::uint64_t>(rep))),
            offset, exhausted);
        seen += v;
        replicate[rep] = unocc * v / k;
      }
      rays[j] = options.samples;
      f[j] = unocc * seen / options.samples;
      var[j] = ff::replicate_variance(replicate, R);
    }
  });
  PointFactors out;
  out.surfaces = mesh.surface_names;
  out.F.assign(out.surfaces.size(), 0.0);
  out.stderr_F.assign(out.surfaces.size(), 0.0);
  for (std::int32_t j = 0; j < np; ++j) {
    out.F[mesh.patches[j].surface] += f[j];
    out.stderr_F[mesh.patches[j].surface] += var[j];
    out.rays += rays[j];
  }
  for (double& v : out.stderr_F) v = std::sqrt(v);
  return out;
}

}  // namespace lambert
