// Exchange factors with participating media: see media.hpp for the estimate.
// Thread safety: rows are computed in parallel, each writing only its own staged row.

#include "geometry/formfactors/media.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/formfactors/reciprocity.hpp"
#include "geometry/formfactors/visibility.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert {
namespace {

using Entry = std::pair<std::int32_t, double>;  // column, value
using Row = std::vector<Entry>;

constexpr std::uint64_t kZoneSalt = 0x7a6f6e65ull;   // "zone"
constexpr std::uint64_t kPatchSalt = 0x6d656469ull;  // "medi"
// Pair streams are salted too: the estimators key their own pair streams hash_keys(seed, i,
// j), and the transmittance's points must not reuse their random numbers.
constexpr std::uint64_t kPairSalt = 0x74726e73ull;  // "trns"

double pair_transmittance(const Medium& medium, const ff::PatchGeom& a, const ff::PatchGeom& b,
                          int samples, std::uint64_t stream) {
  Rng rng(stream);
  double weighted = 0.0, total = 0.0;
  for (int k = 0; k < samples; ++k) {
    double ja;
    const double u0 = rng.uniform(), u1 = rng.uniform();
    const Eigen::Vector3d x = ff::sample_patch(a, u0, u1, ja);
    const ff::KernelSampler sampler(x, a.normal, b);
    if (sampler.empty()) continue;
    bool exhausted = false;
    const double v0 = rng.uniform(), v1 = rng.uniform(), v2 = rng.uniform();
    const Eigen::Vector3d y = sampler.sample(v0, v1, v2, rng, exhausted);
    const double w = ja * sampler.factor();
    if (!(w > 0.0)) continue;
    total += w;
    weighted += w * transmittance(medium, x, y);
  }
  return total > 0.0 ? weighted / total : 1.0;
}

// Walks the segment o + t d, t in [0, t_end], appending each zone's extinguished share
// exp(-tau before)(1 - exp(-sigma_t l)) times `weight` to `out`; returns exp(-tau) of the
// whole segment.
double deposit(const Medium& medium, const Zones& zones, std::int32_t first_column,
               const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_end, double weight,
               Row& out) {
  double tau = 0.0;
  traverse_medium(medium, o, d, 0.0, t_end, [&](std::int32_t v, double a, double b) {
    const std::int32_t z = zones.zone_of[v];
    if (z < 0) return;
    const double dtau = medium.sigma_t(v) * (b - a);
    out.push_back({first_column + z, weight * std::exp(-tau) * -std::expm1(-dtau)});
    tau += dtau;
  });
  return std::exp(-tau);
}

// Sorts a row by column (stably: equal columns keep their order, so every sum is taken in a
// fixed order) and merges duplicates.
void merge_row(Row& row) {
  std::stable_sort(row.begin(), row.end(),
                   [](const Entry& a, const Entry& b) { return a.first < b.first; });
  size_t out = 0;
  for (size_t k = 0; k < row.size(); ++k) {
    if (out > 0 && row[out - 1].first == row[k].first)
      row[out - 1].second += row[k].second;
    else
      row[out++] = row[k];
  }
  row.resize(out);
}

// T̄ of every stored entry of F (compressed), aligned with its storage. Each unordered pair
// is estimated once: at its entry with j > i (pass 1), copied to the mirror entry found by
// binary search in row j (pass 2; estimated there when the mirror is absent). T̄ is a pure
// function of the pair, so the result does not depend on the thread count.
std::vector<double> entry_transmittances(const SparseF& F, const std::vector<ff::PatchGeom>& geom,
                                         const Medium& medium, const MediumFactorOptions& o) {
  const auto* outer = F.outerIndexPtr();
  const auto* cols = F.innerIndexPtr();
  std::vector<double> t(static_cast<size_t>(F.nonZeros()), 0.0);
  const auto estimate = [&](std::int64_t i, std::int64_t j) {
    const auto lo = static_cast<std::int32_t>(std::min(i, j));
    const auto hi = static_cast<std::int32_t>(std::max(i, j));
    return pair_transmittance(medium, geom[lo], geom[hi], o.transmittance_samples,
                              hash_keys(o.seed ^ kPairSalt, lo, hi));
  };
  for (int pass = 0; pass < 2; ++pass)
    parallel_for(F.rows(), 16, o.threads, [&](std::int64_t r0, std::int64_t r1) {
      for (std::int64_t i = r0; i < r1; ++i)
        for (std::int64_t k = outer[i]; k < outer[i + 1]; ++k) {
          const std::int64_t j = cols[k];
          if (pass == 0) {
            if (j > i) t[k] = estimate(i, j);
            continue;
          }
          if (j > i) continue;
          const auto* first = cols + outer[j];
          const auto* last = cols + outer[j + 1];
          const auto* m = std::lower_bound(first, last, i);
          t[k] = j < i && m != last && *m == i ? t[m - cols] : estimate(i, j);
        }
    });
  return t;
}

// Row i < N: the attenuated surface row and the deposits of K cosine rays.
Row patch_row(const PatchMesh& mesh, const std::vector<ff::PatchGeom>& geom, const Medium& medium,
              const Zones& zones, const SparseF& F, const std::vector<double>& transmittances,
              const MediumFactorOptions& o, const Bvh& bvh, std::int32_t i) {
  const std::int32_t n = mesh.size();
  Row row, hit_part, other_part;
  double deficit = 0.0;
  for (std::int64_t k = F.outerIndexPtr()[i]; k < F.outerIndexPtr()[i + 1]; ++k) {
    const double f = F.valuePtr()[k], t = transmittances[k];
    row.push_back({static_cast<std::int32_t>(F.innerIndexPtr()[k]), f * t});
    deficit += f * (1.0 - t);
  }
  const ff::PatchGeom& g = geom[i];
  Eigen::Vector3d t, b;
  ff::orthonormal_frame(g.normal, t, b);
  const double offset = ff::kRayOffset * mesh.scale;
  Rng rng(hash_keys(o.seed ^ kPatchSalt, static_cast<std::uint64_t>(i)));
  for (int k = 0; k < o.rays; ++k) {
    double jac;
    const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
    const Eigen::Vector3d x = ff::sample_patch(g, u0, u1, jac) + ff::end_lift(g, offset) * g.normal;
    const Eigen::Vector3d dir = ff::cosine_direction(g.normal, t, b, u2, u3);
    const RayHit hit = bvh.intersect(x.cast<float>(), dir.cast<float>());
    const bool reaches =
        hit.patch >= 0 && hit.patch != i && dir.dot(mesh.patches[hit.patch].normal) < 0.0;
    const double end = hit.patch >= 0 ? hit.t : std::numeric_limits<double>::infinity();
    deposit(medium, zones, n, x, dir, end, jac / g.area / o.rays, reaches ? hit_part : other_part);
  }
  double taken = 0.0;
  for (const Entry& e : hit_part) taken += e.second;
  const double scale = taken > 0.0 ? deficit / taken : 0.0;
  for (Entry& e : hit_part) e.second *= scale;
  row.insert(row.end(), hit_part.begin(), hit_part.end());
  row.insert(row.end(), other_part.begin(), other_part.end());
  merge_row(row);
  return row;
}

// Zone z's rays: K rays from uniform points of its voxel in uniform directions. Returns the
// zone-to-zone deposits (columns are zone indices) and sets `reached` to the fraction that
// ends in a zone or on the front of a patch (exactly 1 in a closed scene).
Row zone_row(const PatchMesh& mesh, const Medium& medium, const Zones& zones,
             const MediumFactorOptions& o, const Bvh& bvh, std::int32_t z, double& reached) {
  const Eigen::Vector3d lo = medium.voxel_lo(zones.voxel[z]), h = medium.voxel_size();
  Rng rng(hash_keys(o.seed ^ kZoneSalt, static_cast<std::uint64_t>(z)));
  Row row;
  const double w = 1.0 / o.rays;
  reached = 0.0;
  for (int k = 0; k < o.rays; ++k) {
    const Eigen::Vector3d x =
        lo + h.cwiseProduct(Eigen::Vector3d(rng.uniform(), rng.uniform(), rng.uniform()));
    const double cz = 1.0 - 2.0 * rng.uniform(), phi = 2.0 * M_PI * rng.uniform();
    const double sz = std::sqrt(std::max(0.0, 1.0 - cz * cz));
    const Eigen::Vector3d dir(sz * std::cos(phi), sz * std::sin(phi), cz);
    const RayHit hit = bvh.intersect(x.cast<float>(), dir.cast<float>());
    const double end = hit.patch >= 0 ? hit.t : std::numeric_limits<double>::infinity();
    const double through = deposit(medium, zones, 0, x, dir, end, w, row);
    reached += w * (1.0 - through);
    if (hit.patch >= 0 && dir.dot(mesh.patches[hit.patch].normal) < 0.0) reached += w * through;
  }
  merge_row(row);
  return row;
}

// The zone-to-zone block (zones x zones) from the zones' rays, each row scaled to its share
// target[z] (what the zone's rays reached minus the zone-to-patch part already fixed by
// reciprocity), then averaged and balanced (reciprocity.hpp) so that G = A F is symmetric
// and every row keeps that share.
SparseF zone_block(std::vector<Row>& rows, const std::vector<double>& target, const Zones& zones,
                   FormFactorStats& stats, int threads) {
  const std::int32_t m = zones.size();
  std::int64_t nnz = 0;
  for (std::int32_t z = 0; z < m; ++z) {
    double sum = 0.0;
    for (const Entry& e : rows[z]) sum += e.second;
    const double scale = sum > 0.0 ? target[z] / sum : 0.0;
    for (Entry& e : rows[z]) e.second *= scale;
    nnz += static_cast<std::int64_t>(rows[z].size());
  }
  SparseF block(m, m);
  block.reserve(2 * nnz);  // room for the averaged union (at most twice), reciprocity.hpp
  for (std::int32_t z = 0; z < m; ++z) {
    block.startVec(z);
    for (const Entry& e : rows[z])
      if (e.second > 0.0) block.insertBack(z, e.first) = e.second;
    Row().swap(rows[z]);
  }
  block.finalize();
  const std::vector<double> areas(zones.area.data(), zones.area.data() + m);
  ff::average_reciprocal(block, nullptr, areas, stats, threads);
  return block;
}

}  // namespace

double medium_peak_bytes(std::int64_t patches, const Medium& medium, int rays) {
  std::int64_t m = 0;
  for (std::int32_t v = 0; v < medium.voxels(); ++v) m += medium.sigma_t(v) > 0.0;
  const double k = std::max(rays, 1);
  const double r0 = std::sqrt(k / (4.0 * M_PI)), far = medium.resolution.maxCoeff();
  const double seen = 4.0 * M_PI / 3.0 * r0 * r0 * r0 + k * std::max(0.0, far - r0);
  const double row = std::min<double>(static_cast<double>(m), seen);
  const double entries = static_cast<double>(m) * row + 2.0 * patches * row;
  // 16 bytes per entry (value and column), assembled, plus the staged rows: they are freed
  // row by row as the CSR fills, so half of them on average coexist with it.
  constexpr double kEntryBytes = 16.0;
  return 1.5 * kEntryBytes * entries;
}

Zones make_zones(const Medium& medium) {
  Zones z;
  const std::int32_t m = medium.voxels();
  z.zone_of.assign(static_cast<size_t>(m), -1);
  for (std::int32_t v = 0; v < m; ++v)
    if (medium.sigma_t(v) > 0.0) {
      z.zone_of[v] = z.size();
      z.voxel.push_back(v);
    }
  const std::int32_t count = z.size();
  z.area.resize(count);
  z.albedo.resize(count, 3);
  z.emission.resize(count, 3);
  const double volume = medium.voxel_volume();
  for (std::int32_t k = 0; k < count; ++k) {
    const std::int32_t v = z.voxel[k];
    const double st = medium.sigma_t(v);
    z.area[k] = 4.0 * st * volume;
    // min(1, .): sigma_s <= sigma_t up to rounding of the grey check.
    z.albedo.row(k) = (medium.sigma_s.row(v) / st).cwiseMin(1.0);
    z.emission.row(k) = medium.emission.row(v) / (4.0 * st);
  }
  return z;
}

double pair_transmittance(const PatchMesh& mesh, const Medium& medium, std::int32_t a,
                          std::int32_t b, int samples, std::uint64_t seed) {
  const std::vector<ff::PatchGeom> geom = ff::patch_geometry(mesh);
  const std::int32_t lo = std::min(a, b), hi = std::max(a, b);
  return pair_transmittance(medium, geom[lo], geom[hi], samples,
                            hash_keys(seed ^ kPairSalt, lo, hi));
}

FormFactors extend_with_medium(const PatchMesh& mesh, const Medium& medium, const Zones& zones,
                               const FormFactors& surface, const MediumFactorOptions& o,
                               const Bvh& bvh) {
  const Timer timer;
  const std::int32_t n = mesh.size(), total = n + zones.size();
  LAMBERT_CHECK(surface.F.rows() == n && surface.F.cols() == n,
                "surface form factors do not match the mesh");
  LAMBERT_CHECK(o.rays >= 1 && o.transmittance_samples >= 1, "medium factor counts must be >= 1");
  const std::vector<ff::PatchGeom> geom = ff::patch_geometry(mesh);
  SparseF compressed;
  if (!surface.F.isCompressed()) {
    compressed = surface.F;
    compressed.makeCompressed();
  }
  const SparseF& SF = surface.F.isCompressed() ? surface.F : compressed;
  const std::vector<double> trans = entry_transmittances(SF, geom, medium, o);
  const std::int32_t m = zones.size();
  std::vector<Row> rows(static_cast<size_t>(n)), zone_rows(static_cast<size_t>(m));
  std::vector<double> reached(static_cast<size_t>(m), 0.0);
  parallel_for(total, 16, o.threads, [&](std::int64_t r0, std::int64_t r1) {
    for (std::int64_t r = r0; r < r1; ++r) {
      const auto i = static_cast<std::int32_t>(r);
      if (i < n)
        rows[i] = patch_row(mesh, geom, medium, zones, SF, trans, o, bvh, i);
      else
        zone_rows[i - n] = zone_row(mesh, medium, zones, o, bvh, i - n, reached[i - n]);
    }
  });
  // Zone-to-patch entries by reciprocity from the patch rows, F_zi = A_i F_iz / A_z: one
  // estimate per pair. Appended in increasing i, so every zone row is sorted.
  std::vector<Row> cross(static_cast<size_t>(m));
  for (std::int32_t i = 0; i < n; ++i)
    for (const Entry& e : rows[i])
      if (e.first >= n) {
        const std::int32_t z = e.first - n;
        cross[z].push_back({i, mesh.patches[i].area * e.second / zones.area[z]});
      }
  std::vector<double> share(static_cast<size_t>(m));
  for (std::int32_t z = 0; z < m; ++z) {
    double to_patches = 0.0;
    for (const Entry& e : cross[z]) to_patches += e.second;
    share[z] = std::max(0.0, reached[z] - to_patches);
  }
  FormFactors out;
  out.options = surface.options;
  out.options.contents.medium_zones = m;
  out.options.contents.medium_extinction = extinction_hash(medium);
  out.options.contents.medium_rays = o.rays;
  out.options.contents.transmittance_samples = o.transmittance_samples;
  out.stats = surface.stats;
  const SparseF block = zone_block(zone_rows, share, zones, out.stats, o.threads);

  std::int64_t nnz = block.nonZeros();
  for (const Row& row : rows) nnz += static_cast<std::int64_t>(row.size());
  for (const Row& row : cross) nnz += static_cast<std::int64_t>(row.size());
  out.F.resize(total, total);
  out.F.reserve(nnz);
  for (std::int32_t i = 0; i < n; ++i) {
    out.F.startVec(i);
    for (const Entry& e : rows[i]) out.F.insertBack(i, e.first) = e.second;
    Row().swap(rows[i]);
  }
  for (std::int32_t z = 0; z < m; ++z) {
    out.F.startVec(n + z);
    for (const Entry& e : cross[z]) out.F.insertBack(n + z, e.first) = e.second;
    Row().swap(cross[z]);
    for (SparseF::InnerIterator it(block, z); it; ++it)
      out.F.insertBack(n + z, n + it.col()) = it.value();
  }
  out.F.finalize();
  out.stats.rays += static_cast<std::int64_t>(total) * o.rays +
                    static_cast<std::int64_t>(surface.F.nonZeros()) * o.transmittance_samples;
  out.stats.seconds += timer.seconds();
  return out;
}

}  // namespace lambert
