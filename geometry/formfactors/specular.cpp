// Extended form factors' specular part: see specular.hpp for the quantity, the estimate and
// why it is reciprocal.

#include "geometry/formfactors/specular.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/replicates.hpp"
#include "geometry/optics.hpp"

namespace lambert::ff {
namespace {

// One front arrival after >= 1 bounce: patch, replicate, weight (J / A_i) · Π bounces.
struct Arrival {
  std::int32_t j;
  std::int32_t rep;
  double w;
};

// What one row's rays found.
struct RowPaths {
  std::vector<Arrival> arrivals;
  double continued = 0.0;  // Σ over rays of the weight carried on past counted arrivals
  std::int64_t rays = 0;
};

// The bounce a path makes at a specular face: the new direction, the side it leaves from,
// and the weight it carries on (one value: the specular parts are grey).
struct Bounce {
  Eigen::Vector3d dir, side;
  double carried = 0.0;
};

Bounce bounce_at(const Specular& sp, const Eigen::Vector3d& dir, const Eigen::Vector3d& front,
                 Rng& rng) {
  Bounce b;
  if (!sp.dielectric) {
    b.dir = reflect(dir, front);
    b.side = front;
    b.carried = sp.reflectance[0];
    return b;
  }
  const Interface in = dielectric_interface(dir, front, sp.ior);
  // Reflect with probability R, else refract: the expected weight R · 1 + (1 − R) · T is
  // exact, and the path stays one path (no branching).
  if (rng.uniform() < in.reflectance || !refract(dir, in.normal, in.eta, b.dir)) {
    b.dir = reflect(dir, in.normal);
    b.side = in.normal;
    b.carried = 1.0;
  } else {
    b.side = -in.normal;
    b.carried = in.entering ? sp.transmission[0] : 1.0;
  }
  return b;
}

// Row i: K cosine rays followed through specular bounces (see specular.hpp).
void trace_row(const PatchMesh& mesh, const std::vector<PatchGeom>& geom, const Bvh& bvh,
               std::int32_t i, const FormFactorOptions& o, double offset, RowPaths& out) {
  const PatchGeom& g = geom[i];
  Eigen::Vector3d t, b;
  orthonormal_frame(g.normal, t, b);
  out.arrivals.clear();
  out.continued = 0.0;
  out.rays = 0;
  const int K = o.specular.rays;
  const int R = replicate_count(K);
  for (int rep = 0; rep < R; ++rep) {
    const Kronecker4 seq(hash_keys(o.run.seed ^ 0x73706563756c6172ull,  // "specular"
                                   static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(rep)));
    Rng rng(hash_keys(o.run.seed, static_cast<std::uint64_t>(i), 0x10000ull + rep));
    const int k = replicate_size(K, rep);
    for (int s = 0; s < k; ++s) {
      double jac;
      const Eigen::Vector3d x = sample_patch(g, seq.get(s, 0), seq.get(s, 1), jac);
      Eigen::Vector3d dir = cosine_direction(g.normal, t, b, seq.get(s, 2), seq.get(s, 3));
      Eigen::Vector3d origin = x + end_lift(g, offset) * g.normal;
      double w = jac / g.area;
      for (int bounce = 0;; ++bounce) {
        const RayHit hit = bvh.intersect(origin.cast<float>(), dir.cast<float>());
        ++out.rays;
        if (hit.patch < 0 || (bounce == 0 && hit.patch == i)) break;
        const Eigen::Vector3d& n = geom[hit.patch].normal;
        const bool front = dir.dot(n) < 0.0;
        if (front && bounce > 0) out.arrivals.push_back({hit.patch, rep, w});
        const Specular* sp = mesh.specular_of(hit.patch);
        if (!sp || (!front && !sp->dielectric) || bounce == o.specular.depth) break;
        const Bounce next = bounce_at(*sp, dir, n, rng);
        if (front) out.continued += w * next.carried;
        w *= next.carried;
        if (!(w > 0.0)) break;
        origin = origin + static_cast<double>(hit.t) * dir + offset * next.side;
        dir = next.dir;
      }
    }
  }
  out.continued /= K;
}

// Row i's entries (i, j, S_ij) and, with errors, their replicate standard errors.
void row_entries(std::int32_t i, std::vector<Arrival>& arrivals, int K, bool with_err,
                 std::vector<Eigen::Triplet<double, std::int64_t>>& values,
                 std::vector<Eigen::Triplet<double, std::int64_t>>& errors) {
  std::stable_sort(arrivals.begin(), arrivals.end(),
                   [](const Arrival& a, const Arrival& b) { return a.j < b.j; });
  const int R = replicate_count(K);
  for (size_t h = 0; h < arrivals.size();) {
    const std::int32_t j = arrivals[h].j;
    double per_rep[kReplicates] = {};
    double sum = 0.0;
    for (; h < arrivals.size() && arrivals[h].j == j; ++h) {
      per_rep[arrivals[h].rep] += arrivals[h].w;
      sum += arrivals[h].w;
    }
    values.emplace_back(i, j, sum / K);
    if (!with_err) continue;
    for (int r = 0; r < R; ++r) per_rep[r] /= replicate_size(K, r);
    errors.emplace_back(i, j, std::sqrt(replicate_variance(per_rep, R)));
  }
}

// G = (A_i S_ij + A_j S_ji) / 2 back to factors; variances of the two independent sides
// average likewise (V = (A_i² σ_ij² + A_j² σ_ji²) / 4).
void average_sides(SparseF& S, SparseF* err, const Eigen::VectorXd& area) {
  const Eigen::VectorXd inv = area.cwiseInverse();
  SparseF G = area.asDiagonal() * S;
  SparseF Gt = G.transpose();
  SparseF sym = 0.5 * (G + Gt);
  S = inv.asDiagonal() * sym;
  S.makeCompressed();
  if (!err) return;
  SparseF V = (area.asDiagonal() * *err).cwiseAbs2();
  SparseF Vt = V.transpose();
  SparseF mean = 0.25 * (V + Vt);
  // The union pattern of G and Gᵀ is V's and Vᵀ's: the errors keep S's pattern.
  *err = inv.asDiagonal() * SparseF(mean.cwiseSqrt());
  err->makeCompressed();
}

}  // namespace

void check_grey_specular(const PatchMesh& mesh) {
  for (size_t s = 0; s < mesh.surface_specular.size(); ++s) {
    const Specular& sp = mesh.surface_specular[s];
    if (!sp.any()) continue;
    const Eigen::Vector3d& v = sp.dielectric ? sp.transmission : sp.reflectance;
    if (v.maxCoeff() - v.minCoeff() > 0.0)
      throw SceneError("surface '" + mesh.surface_names[s] + "': " +
                       (sp.dielectric ? "transmission Tf" : "specular reflectance Ks") +
                       " differs between channels: extended form factors carry one weight for "
                       "all three (give a grey value, or --specular-depth 0 to let specular "
                       "surfaces only receive and block)");
  }
}

SpecularTransport compute_specular_transport(const PatchMesh& mesh,
                                             const FormFactorOptions& options, const Bvh& bvh,
                                             bool average) {
  LAMBERT_CHECK(mesh.has_specular(), "specular transport on a diffuse mesh");
  if (options.specular.rays < 1) throw UsageError("--specular-rays must be at least 1");
  if (options.run.with_stderr && options.specular.rays < 4)
    throw UsageError("--stderr needs --specular-rays of at least 4 (standard errors come from "
                     "independent replicates)");
  check_grey_specular(mesh);
  const std::int32_t n = mesh.size();
  const std::vector<PatchGeom> geom = patch_geometry(mesh);
  const double offset = kRayOffset * mesh.scale;
  SpecularTransport out;
  out.continued = Eigen::VectorXd::Zero(n);
  // Rows in blocks (the arrivals of a block are staged, then turned into triplets in row
  // order: deterministic for any thread count).
  constexpr std::int32_t kBlock = 4096;
  std::vector<RowPaths> rows(std::min(n, kBlock));
  std::vector<Eigen::Triplet<double, std::int64_t>> values, errors;
  Progress progress("specular", options.run.progress ? n : 0, "rays");
  for (std::int32_t block = 0; block < n; block += kBlock) {
    const std::int32_t count = std::min(kBlock, n - block);
    parallel_for(count, 16, options.run.threads, [&](std::int64_t begin, std::int64_t end) {
      for (std::int64_t r = begin; r < end; ++r) {
        trace_row(mesh, geom, bvh, static_cast<std::int32_t>(block + r), options, offset,
                  rows[r]);
        progress.advance(1, rows[r].rays);
      }
    });
    for (std::int32_t r = 0; r < count; ++r) {
      out.continued[block + r] = rows[r].continued;
      out.rays += rows[r].rays;
      row_entries(block + r, rows[r].arrivals, options.specular.rays, options.run.with_stderr,
                  values, errors);
    }
  }
  progress.finish();
  out.S.resize(n, n);
  out.S.setFromTriplets(values.begin(), values.end());
  Eigen::VectorXd area(n);
  for (std::int32_t i = 0; i < n; ++i) area[i] = mesh.patches[i].area;
  if (options.run.with_stderr) {
    out.stderr_S.resize(n, n);
    out.stderr_S.setFromTriplets(errors.begin(), errors.end());
  }
  if (average) average_sides(out.S, options.run.with_stderr ? &out.stderr_S : nullptr, area);
  return out;
}

void add_specular_transport(const PatchMesh& mesh, const FormFactorOptions& options,
                            const Bvh& bvh, FormFactors& out) {
  const Timer timer;
  SpecularTransport sp = compute_specular_transport(mesh, options, bvh);
  SparseF sum = out.F + sp.S;
  out.F.swap(sum);
  out.F.makeCompressed();
  if (options.run.with_stderr) {
    SparseF var = SparseF(out.stderr_F.cwiseAbs2()) + SparseF(sp.stderr_S.cwiseAbs2());
    out.stderr_F = var.cwiseSqrt();
    out.stderr_F.makeCompressed();
  }
  out.specular_continued = std::move(sp.continued);
  out.stats.specular_rays = sp.rays;
  out.stats.rays += sp.rays;
  out.stats.seconds += timer.seconds();
}

}  // namespace lambert::ff
