#include "geometry/render/pixel_direct.hpp"

#include <algorithm>
#include <array>

#include "core/error.hpp"
#include "core/sampling.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/visibility.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

ff::PatchGeom piece_of(const std::vector<Eigen::Vector3d>& corners) {
  ff::PatchGeom g;
  g.n = static_cast<int>(corners.size());
  for (int k = 0; k < g.n; ++k) g.p[k] = corners[k];
  if (g.n == 3) g.p[3] = g.p[2];
  const Eigen::Vector3d newell = newell_normal(corners);
  g.area = 0.5 * newell.norm();
  g.normal = newell.normalized();
  g.centroid = Eigen::Vector3d::Zero();
  for (const auto& c : corners) g.centroid += c / g.n;
  g.diameter = polygon_diameter(corners);
  g.warp = ff::quad_warp(g.p, g.n, g.normal);
  return g;
}

}  // namespace

PixelDirectLight::PixelDirectLight(const Scene& scene, int rays, double offset)
    : rays_(rays), offset_(offset) {
  LAMBERT_CHECK(rays >= 1, "PixelDirectLight: at least one ray per query");
  for (const Face& face : scene.faces) {
    const Eigen::Vector3d E = scene.material_of(face.surface).emission;
    if (!(E.maxCoeff() > 0.0)) continue;
    std::vector<Eigen::Vector3d> corners;
    for (auto v : face.vertices) corners.push_back(scene.vertices[v]);
    if (is_degenerate_polygon(corners)) continue;
    if (corners.size() == 3 || (corners.size() == 4 && is_convex(corners))) {
      pieces_.push_back(piece_of(corners));
      emission_.push_back(E);
    } else if (corners.size() <= static_cast<size_t>(kMaxPieces) + 2) {
      for (const auto& t : triangulate(corners)) {  // the mesher triangulated it already
        pieces_.push_back(piece_of({corners[t[0]], corners[t[1]], corners[t[2]]}));
        emission_.push_back(E);
      }
    }
    if (pieces_.size() > static_cast<size_t>(kMaxPieces) ||
        corners.size() > static_cast<size_t>(kMaxPieces) + 2) {
      why_ = "more than " + std::to_string(kMaxPieces) + " emitting faces (or triangles of them)";
      pieces_.clear();
      emission_.clear();
      return;
    }
  }
}

Eigen::Vector3d PixelDirectLight::irradiance(const Bvh& bvh, const Eigen::Vector3d& x,
                                             const Eigen::Vector3d& n, std::uint64_t stream,
                                             std::int64_t first, std::int64_t& cast) const {
  // One sampler per piece in front of x (its exact unoccluded factor comes with it), and
  // the luminance weights w_e = (E_R + E_G + E_B) F(x → e) that pick a piece per ray.
  thread_local std::vector<ff::KernelSampler> samplers;
  thread_local std::vector<std::int32_t> which;
  thread_local std::vector<double> cdf;
  samplers.clear();
  which.clear();
  cdf.clear();
  double total = 0.0;
  for (size_t e = 0; e < pieces_.size(); ++e) {
    const ff::PatchGeom& g = pieces_[e];
    if (!(g.normal.dot(x - g.centroid) > 0.0)) continue;  // x behind the piece or on it
    ff::KernelSampler s(x, n, g);
    if (s.empty() || !(s.factor() > 0.0)) continue;
    total += emission_[e].sum() * s.factor();
    samplers.push_back(s);
    which.push_back(static_cast<std::int32_t>(e));
    cdf.push_back(total);
  }
  if (!(total > 0.0)) return Eigen::Vector3d::Zero();
  // Ray r picks piece e with probability p_e = w_e / total (stratified by the first
  // coordinate) and adds E_e F(x → e) V / (p_e rays): exact when every ray sees its piece.
  const Kronecker4 seq(stream);
  Rng rng(hash_keys(stream, static_cast<std::uint64_t>(first)));  // the rejections' numbers
  Eigen::Vector3d H = Eigen::Vector3d::Zero();
  for (std::int64_t r = first; r < first + rays_; ++r) {
    const double pick = seq.get(r, 0) * total;
    size_t k = 0;
    while (k + 1 < cdf.size() && pick >= cdf[k]) ++k;
    const double below = k ? cdf[k - 1] : 0.0;
    const double width = cdf[k] - below;
    const double u0 = std::clamp((pick - below) / width, 0.0, std::nextafter(1.0, 0.0));
    bool gave_up = false;  // never seen in practice (KernelSampler): y is then still on e
    const Eigen::Vector3d y = samplers[k].sample(u0, seq.get(r, 1), seq.get(r, 2), rng, gave_up);
    ++cast;
    const ff::PatchGeom& g = pieces_[which[k]];
    if (!ff::visible(bvh, x, n, offset_, y, g.normal, ff::end_lift(g, offset_))) continue;
    // E_e F / p_e = E_e F total / w_e = E_e total / ΣE_e.
    H += emission_[which[k]] * (total / emission_[which[k]].sum());
  }
  return H / rays_;
}

}  // namespace lambert
