#include "geometry/formfactors/reference.hpp"

#include <algorithm>

#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/kernels.hpp"

namespace lambert {
namespace {

using namespace ff;

// (1/A_a) ∫_{A_a} F(x -> b) dA_x by composite Gauss-Legendre: s x s cells of order m in
// patch a's parameter square. The integrand is smooth for distant pairs: the relative error
// falls like (size/2d)^(2m) (see hybrid.cpp), so order 4 past 6 diameters ((1/12)^8 ~ 2e-9)
// and order 8 past 3 ((1/6)^16 ~ 3e-13) suffice. It has a
// log-singular derivative along an edge shared with b, which 6 x 6 cells of order 16
// (9216 nodes) resolve to ~1e-8 (checked against Howell C-14 for the shared-edge case).
double quadrature_factor(const PatchGeom& a, const PatchGeom& b) {
  const double q = (a.centroid - b.centroid).norm() / std::max(a.diameter, b.diameter);
  const int cells = q > 3.0 ? 1 : q > 1.2 ? 2 : 6;
  const int order = q > 6.0 ? 4 : q > 3.0 ? 8 : 16;
  const GaussRule rule = gauss_legendre(order);
  double sum = 0.0;
  for (int cu = 0; cu < cells; ++cu)
    for (int cv = 0; cv < cells; ++cv)
      for (int u = 0; u < order; ++u)
        for (int v = 0; v < order; ++v) {
          double jac;
          const Eigen::Vector3d x = quadrature_point(a, (cu + rule.x[u]) / cells,
                                                         (cv + rule.x[v]) / cells, jac);
          sum += rule.w[u] * rule.w[v] * jac * point_to_patch(x, a.normal, b);
        }
  return sum / (cells * cells * a.area);
}

}  // namespace

// The per-patch quadrature reference for unoccluded (analytic) cases, rows in parallel.
FormFactors unoccluded_quadrature(const PatchMesh& mesh, int threads) {
  Timer timer;
  const std::vector<PatchGeom> geom = patch_geometry(mesh);
  const std::int32_t n = mesh.size();
  const double eps = 1e-12 * mesh.scale;  // as kPlaneEps in formfactors.cpp
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
