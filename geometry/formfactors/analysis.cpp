#include "geometry/formfactors/analysis.hpp"

#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <sstream>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/mirror.hpp"
#include "geometry/formfactors/pairwise.hpp"
#include "geometry/formfactors/replicates.hpp"
#include "geometry/formfactors/visibility.hpp"

namespace lambert {
namespace {

// 'a', 'b' and N more: surface names for a one-line message.
std::string surface_list(const PatchMesh& mesh, const std::vector<std::int32_t>& surfaces) {
  constexpr size_t kNamed = 5;  // enough to recognise the surfaces, short enough for one line
  std::string names;
  for (size_t k = 0; k < std::min(kNamed, surfaces.size()); ++k)
    names += (k ? ", '" : "'") + mesh.surface_names.at(surfaces[k]) + "'";
  if (surfaces.size() > kNamed)
    names += " and " + std::to_string(surfaces.size() - kNamed) + " more";
  return names;
}

}  // namespace

FormFactorDiagnostics diagnose(const PatchMesh& mesh, const SparseF& F, int worst, int threads) {
  FormFactorDiagnostics d;
  d.n = static_cast<std::int32_t>(F.rows());
  d.nnz = F.nonZeros();
  d.row_sum_histogram.assign(FormFactorDiagnostics::kHistogramBins, 0);
  // Rows in parallel, each into its own slot (sums in storage order); the counts and maxima
  // are reduced in row order afterwards: the same for any thread count.
  struct RowFacts {
    std::int64_t negative = 0, above_one = 0;
    double reciprocity_max = 0.0, reciprocity_max_relative = 0.0;
  };
  std::vector<double> sums(d.n, 0.0);
  std::vector<RowFacts> facts(d.n);
  const auto* outer = F.outerIndexPtr();
  const auto* col = F.innerIndexPtr();
  const std::uint64_t call = ff::MirrorCursor::next_call();
  const bool compressed = F.isCompressed();  // (outer[j + 1] ends row j)
  std::vector<double> area(d.n);             // side by side: a Patch per entry missed the cache
  for (std::int32_t i = 0; i < d.n; ++i) area[i] = mesh.patches[i].area;
  parallel_for(d.n, 256, threads, [&](std::int64_t begin, std::int64_t end) {
    thread_local ff::MirrorCursor mirror;
    mirror.rows(d.n);
    for (std::int64_t i = begin; i < end; ++i) {
      RowFacts& r = facts[i];
      for (SparseF::InnerIterator it(F, i); it; ++it) {
        sums[i] += it.value();
        r.negative += it.value() < 0.0;
        r.above_one += it.value() > 1.0;
        // F is row-major: F_ji from row j (0 where it is not stored).
        const auto j = static_cast<SparseF::StorageIndex>(it.col());
        double fji = 0.0;
        if (compressed) {
          const std::int64_t q =
              mirror.find(col, outer, j, static_cast<SparseF::StorageIndex>(i), call);
          if (q >= 0) fji = F.valuePtr()[q];
        } else {
          fji = F.coeff(j, i);
        }
        const double aij = area[i] * it.value();
        const double aji = area[j] * fji;
        const double diff = std::abs(aij - aji);
        r.reciprocity_max = std::max(r.reciprocity_max, diff);
        r.reciprocity_max_relative =
            std::max(r.reciprocity_max_relative, diff / std::max(std::abs(aij), std::abs(aji)));
      }
    }
  });
  for (std::int32_t i = 0; i < d.n; ++i) {
    d.negative += facts[i].negative;
    d.above_one += facts[i].above_one;
    d.reciprocity_max = std::max(d.reciprocity_max, facts[i].reciprocity_max);
    d.reciprocity_max_relative =
        std::max(d.reciprocity_max_relative, facts[i].reciprocity_max_relative);
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

LightingProblems find_lighting_problems(const PatchMesh& mesh, const SparseF& F) {
  const std::int32_t n = mesh.size();
  LAMBERT_CHECK(F.rows() == n && F.cols() == n, "F does not match the mesh");
  LightingProblems p;
  p.pairs = static_cast<std::int64_t>(n) * (n - 1) / 2;
  const auto surfaces = mesh.surface_names.size();
  std::vector<char> emits(surfaces, 0), sees(surfaces, 0);
  bool any_visible = false;
  for (std::int32_t i = 0; i < n; ++i) {
    const Patch& patch = mesh.patches[i];
    bool row_sees = false;
    for (SparseF::InnerIterator it(F, i); it && !row_sees; ++it) row_sees = it.value() > 0.0;
    any_visible = any_visible || row_sees;
    if (patch.emission.maxCoeff() > 0.0) {
      emits.at(patch.surface) = 1;
      sees.at(patch.surface) = sees.at(patch.surface) || row_sees;
    }
  }
  p.no_emitter = std::find(emits.begin(), emits.end(), 1) == emits.end();
  p.nothing_visible = n >= 2 && !any_visible;
  if (!p.nothing_visible)
    for (size_t s = 0; s < surfaces; ++s)
      if (emits[s] && !sees[s]) p.blind_emitters.push_back(static_cast<std::int32_t>(s));
  return p;
}

std::vector<std::string> lighting_warnings(const PatchMesh& mesh, const LightingProblems& p) {
  std::vector<std::string> lines;
  if (p.no_emitter)
    lines.push_back("no surface emits: every radiosity is 0; give a material Ke in the MTL");
  if (p.nothing_visible)
    lines.push_back("no patch faces any other (F is zero for all " + std::to_string(p.pairs) +
                    " patch pairs): the scene may be inside out or its winding inverted — "
                    "lambert lights the front (counter-clockwise) side");
  if (!p.blind_emitters.empty()) {
    const std::string names = surface_list(mesh, p.blind_emitters);
    const bool one = p.blind_emitters.size() == 1;
    lines.push_back(std::string(one ? "emitter " : "emitters ") + names + (one ? " sees" : " see") +
                    " nothing from " + (one ? "its" : "their") +
                    " front side: " + (one ? "its normal" : "their normals") +
                    " may point away from the scene (inverted winding)");
  }
  return lines;
}

namespace {

// Why this finds exactly the singular case. K = I - diag(rho) F with F >= 0 and row sums
// <= 1 is singular iff diag(rho) F has eigenvalue 1, which for a non-negative matrix whose
// row sums are <= 1 happens iff some set S keeps all of its rows' mass: rho_i sum_{j in S}
// F_ij = 1 for every i in S (diag(rho) F restricted to S is stochastic; its all-ones vector
// is the eigenvector). That needs rho_i = 1 on S, so S lies within the lossless patches L.
// The largest such S is found by pruning: start from L and repeatedly drop a patch whose
// leak, 1 - sum_{j still in the set} F_ij (what escapes, is absorbed elsewhere, or reaches a
// dropped patch), exceeds its row's error; dropping only raises the others' leaks, so the
// result is the greatest fixpoint, and any closed S survives (no row of it ever leaks).
// A worklist over the lossless-to-lossless entries (column access from a transposed copy
// of just those) makes it O(N + nnz).
// The closed lossless set of one channel, empty if none.
ClosedLossless closed_lossless_set(const PatchMesh& mesh, const FormFactors& ff, int channel) {
  const SparseF& F = ff.F;
  const std::int32_t n = mesh.size();
  std::vector<char> in(n, 0);
  for (std::int32_t i = 0; i < n; ++i) in[i] = mesh.patches[i].rho[channel] >= 1.0;
  ClosedLossless out;
  if (std::find(in.begin(), in.end(), 1) == in.end()) return out;
  const bool have_err = ff.stderr_F.nonZeros() > 0;
  std::vector<double> inside(n, 0.0), tol(n, kClosedRowTolerance);
  std::vector<Eigen::Triplet<double, std::int32_t>> into;  // (row, column) inside L
  for (std::int32_t i = 0; i < n; ++i) {
    if (!in[i]) continue;
    double var = 0.0;
    // stderr_F shares F's sparsity pattern: walk both CSR arrays by position.
    for (auto k = F.outerIndexPtr()[i]; k < F.outerIndexPtr()[i + 1]; ++k) {
      const std::int32_t j = F.innerIndexPtr()[k];
      if (have_err) var += std::pow(ff.stderr_F.valuePtr()[k], 2);
      if (!in[j]) continue;
      inside[i] += F.valuePtr()[k];
      into.emplace_back(i, j, F.valuePtr()[k]);
    }
    tol[i] += kClosedSigmas * std::sqrt(var);
  }
  Eigen::SparseMatrix<double, Eigen::ColMajor, std::int32_t> by_column(n, n);
  by_column.setFromTriplets(into.begin(), into.end());
  std::vector<std::int32_t> drop;
  for (std::int32_t i = 0; i < n; ++i)
    if (in[i] && 1.0 - inside[i] > tol[i]) drop.push_back(i);
  while (!drop.empty()) {
    const std::int32_t j = drop.back();
    drop.pop_back();
    if (!in[j]) continue;
    in[j] = 0;
    for (decltype(by_column)::InnerIterator it(by_column, j); it; ++it) {
      const auto i = static_cast<std::int32_t>(it.row());
      if (!in[i]) continue;
      inside[i] -= it.value();
      if (1.0 - inside[i] > tol[i]) drop.push_back(i);
    }
  }
  for (std::int32_t i = 0; i < n; ++i) {
    if (!in[i]) continue;
    out.patches.push_back(i);
    out.surfaces.push_back(mesh.patches[i].surface);
    out.max_leak = std::max(out.max_leak, 1.0 - inside[i]);
  }
  std::sort(out.surfaces.begin(), out.surfaces.end());
  out.surfaces.erase(std::unique(out.surfaces.begin(), out.surfaces.end()), out.surfaces.end());
  if (!out.patches.empty()) out.channels.push_back(channel);
  return out;
}

}  // namespace

std::vector<ClosedLossless> find_closed_lossless(const PatchMesh& mesh, const FormFactors& ff) {
  LAMBERT_CHECK(ff.F.rows() == mesh.size() && ff.F.cols() == mesh.size(),
                "F does not match the mesh");
  std::vector<ClosedLossless> out;
  for (int c = 0; c < 3; ++c) {
    ClosedLossless set = closed_lossless_set(mesh, ff, c);
    if (set.patches.empty()) continue;
    auto same = std::find_if(out.begin(), out.end(),
                             [&](const ClosedLossless& o) { return o.patches == set.patches; });
    if (same != out.end()) {
      same->channels.push_back(c);
      same->max_leak = std::max(same->max_leak, set.max_leak);
    } else {
      out.push_back(std::move(set));
    }
  }
  return out;
}

std::string closed_lossless_message(const PatchMesh& mesh, const ClosedLossless& c) {
  static const char* const kChannel[] = {"R", "G", "B"};
  std::string channels;
  for (size_t k = 0; k < c.channels.size(); ++k)
    channels += (k ? ", " : "") + std::string(kChannel[c.channels[k]]);
  const bool one = c.surfaces.size() == 1;
  std::ostringstream leak;
  leak << std::setprecision(2) << std::max(0.0, c.max_leak);
  return std::string(one ? "surface " : "surfaces ") + surface_list(mesh, c.surfaces) + " (" +
         std::to_string(c.patches.size()) + " patches) " + (one ? "is" : "are") +
         " lossless (reflectance 1) in channel " + channels +
         " and no light leaves them (none escapes or reaches a surface that absorbs; largest "
         "row leak " +
         leak.str() +
         ", within F's error): I - rho F is singular "
         "and no solver can converge; give one of them a reflectance below 1, or clamp with "
         "--max-reflectance 0.99";
}

SurfaceFactors surface_factors(const PatchMesh& mesh, const FormFactors& ff,
                               const Eigen::VectorXd* zone_area) {
  SurfaceFactors out;
  const std::int32_t n = mesh.size();
  const Eigen::Index zones = zone_area ? zone_area->size() : 0;
  LAMBERT_CHECK(ff.F.rows() == n + zones, "F does not hold the patches and the zones");
  const auto surfaces = static_cast<Eigen::Index>(mesh.surface_names.size());
  const Eigen::Index s = surfaces + (zones > 0 ? 1 : 0);
  out.surfaces = mesh.surface_names;
  if (zones > 0) out.surfaces.push_back(kMediumGroup);
  out.areas.assign(s, 0.0);
  out.F = Eigen::MatrixXd::Zero(s, s);
  Eigen::MatrixXd var = Eigen::MatrixXd::Zero(s, s);
  // stderr_F shares F's sparsity pattern when it is there (a medium's zones carry none).
  out.has_stderr = ff.stderr_F.nonZeros() > 0 && ff.stderr_F.nonZeros() == ff.F.nonZeros();
  auto group = [&](Eigen::Index u) { return u < n ? mesh.patches[u].surface : surfaces; };
  for (Eigen::Index i = 0; i < n + zones; ++i) {
    const Eigen::Index g = group(i);
    const double area = i < n ? mesh.patches[i].area : (*zone_area)[i - n];
    out.areas[g] += area;
    for (auto k = ff.F.outerIndexPtr()[i]; k < ff.F.outerIndexPtr()[i + 1]; ++k) {
      const Eigen::Index h = group(ff.F.innerIndexPtr()[k]);
      out.F(g, h) += area * ff.F.valuePtr()[k];
      if (out.has_stderr) var(g, h) += std::pow(area * ff.stderr_F.valuePtr()[k], 2);
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

SurfaceFactors medium_surface_factors(const PatchMesh& mesh, const FormFactors& surface,
                                      const FormFactors& extended, const Medium& medium,
                                      const Zones& zones, const MediumFactorOptions& o,
                                      const Bvh& bvh) {
  constexpr int R = kMediumReplicates;
  MediumFactorOptions part = o;
  part.rays = std::max(1, (o.rays + R - 1) / R);
  part.transmittance_samples = std::max(1, (o.transmittance_samples + R - 1) / R);
  std::vector<SurfaceFactors> tables;
  for (int r = 0; r < R; ++r) {
    part.seed = hash_keys(o.seed, 0x7265706cull, static_cast<std::uint64_t>(r));  // "repl"
    tables.push_back(surface_factors(
        mesh, extend_with_medium(mesh, medium, zones, surface, part, bvh), &zones.area));
  }
  SurfaceFactors out = surface_factors(mesh, extended, &zones.area);
  // The medium's group is the last (none when no voxel extinguishes: m = s).
  const Eigen::Index s = out.F.rows(), m = zones.size() > 0 ? s - 1 : s;
  Eigen::MatrixXd var = Eigen::MatrixXd::Zero(s, s);
  for (Eigen::Index g = 0; g < s; ++g)
    for (Eigen::Index h = 0; h < s; ++h) {
      double est[R];
      for (int r = 0; r < R; ++r) est[r] = tables[r].F(g, h);
      var(g, h) = ff::replicate_variance(est, R);
    }
  const SurfaceFactors plain = surface_factors(mesh, surface);
  if (plain.has_stderr) {
    const Eigen::MatrixXd vf = plain.stderr_F.cwiseAbs2();
    var.topLeftCorner(m, m) += vf;
    double into_medium = 0.0;
    for (Eigen::Index g = 0; g < m && m < s; ++g) {
      var(g, m) += vf.row(g).sum();
      const double r = out.areas[g] / out.areas[m];
      var(m, g) += vf.row(g).sum() * r * r;
      into_medium += vf.row(g).sum() * r * r;
    }
    if (m < s) var(m, m) += into_medium;
  }
  out.stderr_F = var.cwiseSqrt();
  out.has_stderr = true;
  return out;
}

PointFactors point_form_factors(const PatchMesh& mesh, const Eigen::Vector3d& point,
                                const Eigen::Vector3d& normal, const FormFactorOptions& options) {
  if (!point.allFinite() || !(normal.norm() > 0.0) || !normal.allFinite())
    throw UsageError("--point and --normal must be finite and the normal non-zero");
  const Eigen::Vector3d n = normal.normalized();
  const std::vector<ff::PatchGeom> geom = ff::patch_geometry(mesh);
  const Bvh bvh(mesh, options.run.threads);
  const double offset = ff::kRayOffset * mesh.scale;
  const std::int32_t np = mesh.size();
  std::vector<double> f(np, 0.0), var(np, 0.0);
  std::vector<std::int64_t> rays(np, 0);
  parallel_for(np, 64, options.run.threads, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t jj = b; jj < e; ++jj) {
      const auto j = static_cast<std::int32_t>(jj);
      const double unocc = ff::point_to_patch(point, n, geom[j]);
      if (unocc <= 0.0) continue;
      if (options.estimator == "analytic") {  // exact: the visible part by the booleans
        f[j] = ff::exact_point_factor(bvh, geom, j, point, n);
        continue;
      }
      // The shared visible-fraction kernel (visibility.hpp), in replicates for the error.
      const int R = ff::replicate_count(options.pair.samples);
      double replicate[ff::kReplicates];
      int seen = 0, exhausted = 0;
      for (int rep = 0; rep < R; ++rep) {
        const int k = ff::replicate_size(options.pair.samples, rep);
        const int v = ff::count_visible(bvh, point, n, offset, geom[j], k,
                                        hash_keys(options.run.seed, 0xFFFFFFFFull,
                                                  hash_keys(j, static_cast<std::uint64_t>(rep))),
                                        offset, exhausted);
        seen += v;
        replicate[rep] = unocc * v / k;
      }
      rays[j] = options.pair.samples;
      f[j] = unocc * seen / options.pair.samples;
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
