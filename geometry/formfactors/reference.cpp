#include "geometry/formfactors/reference.hpp"

#include <algorithm>

#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/quadrature.hpp"

namespace lambert {
namespace {

using namespace ff;

// F_ab = G0 / A_a by the adaptive quadrature at reference accuracy (quadrature.hpp),
// integrated over the smaller patch (where the integrand is smoothest).
double quadrature_factor(const PatchGeom& a, const PatchGeom& b) {
  thread_local std::vector<QuadCell> cells;
  const double G = a.area <= b.area ? integrate_unoccluded(a, b, kReferenceAccuracy, cells)
                                    : integrate_unoccluded(b, a, kReferenceAccuracy, cells);
  return G / a.area;
}

}  // namespace

// The per-patch quadrature reference for unoccluded (analytic) cases, rows in parallel.
FormFactors unoccluded_quadrature(const PatchMesh& mesh, int threads) {
  Timer timer;
  const std::vector<PatchGeom> geom = patch_geometry(mesh);
  const std::int32_t n = mesh.size();
  const double eps = kPlaneEps * mesh.scale;
  std::vector<std::vector<std::pair<std::int32_t, double>>> rows(n);
  parallel_for(n, 1, threads, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t i = b; i < e; ++i)
      for (std::int32_t j = 0; j < n; ++j) {
        if (j == i || !can_exchange(geom[i], geom[j], eps)) continue;
        const double f = quadrature_factor(geom[i], geom[j]);
        if (f > 0.0) rows[i].emplace_back(j, f);
      }
  });
  std::vector<Eigen::Triplet<double, std::int32_t>> t;
  for (std::int32_t i = 0; i < n; ++i)
    for (const auto& [j, f] : rows[i]) t.emplace_back(i, j, f);
  FormFactors out;
  out.F.resize(n, n);
  out.F.setFromTriplets(t.begin(), t.end());
  out.options.estimator = "quadrature";
  out.stats.seconds = timer.seconds();
  return out;
}

double proximity(const PatchMesh& mesh, std::int32_t i, std::int32_t j) {
  auto diameter = [&](std::int32_t p) {
    const auto c = mesh.corners(p);
    double d = 0.0;
    for (size_t a = 0; a < c.size(); ++a)
      for (size_t b = a + 1; b < c.size(); ++b) d = std::max(d, (c[a] - c[b]).norm());
    return d;
  };
  const double size = std::max(diameter(i), diameter(j));
  return (mesh.patches[i].centroid - mesh.patches[j].centroid).norm() / std::max(size, 1e-300);
}

}  // namespace lambert
