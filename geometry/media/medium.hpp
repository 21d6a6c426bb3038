#pragma once
// Participating media: an axis-aligned box split into voxels, each with constant absorption
// σa, scattering σs (isotropic phase function) and emission e per channel, and the exact
// optical depth of a segment through them.
//
// Units: σa, σs in 1/scene unit; e in W per scene unit³ (the scene's emission units times
// length⁻¹). The extinction σt = σa + σs must be grey (the same in every channel): the
// exchange factors between zones are then channel-independent, so one F serves the three
// channels like the surfaces' F; colour lives in the albedo ω = σs/σt and in e.
//
// Optical depth τ(a, b) = ∫ σt ds along the segment is piecewise linear in the voxels'
// constant σt, so it is computed exactly by visiting the voxels the segment crosses (a 3-D
// DDA, Amanatides & Woo 1987): τ = Σ_v σt_v ℓ_v with ℓ_v the length inside voxel v. Along a
// ray the transmittance to voxel v's entry is exp(−τ_before) and the fraction extinguished
// inside it 1 − exp(−σt_v ℓ_v): closed-form per segment, no marching step.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

namespace lambert {

/// A voxel grid of participating medium (x fastest, then y, then z).
struct Medium {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();          ///< lower corner (scene units)
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();          ///< upper corner
  Eigen::Vector3i resolution = Eigen::Vector3i::Zero();  ///< voxels per axis
  Eigen::MatrixX3d sigma_a;   ///< per voxel absorption (1/unit), one row per voxel
  Eigen::MatrixX3d sigma_s;   ///< per voxel scattering (1/unit), isotropic
  Eigen::MatrixX3d emission;  ///< per voxel emitted power per volume (W/unit³)
  /// Where the medium came from, for reports ("box ..." or the grid file).
  std::string source;

  /// Number of voxels (0 for no medium).
  std::int32_t voxels() const { return resolution.prod(); }
  /// Edge lengths of one voxel.
  Eigen::Vector3d voxel_size() const { return (hi - lo).cwiseQuotient(resolution.cast<double>()); }
  /// Volume of one voxel (unit³).
  double voxel_volume() const { return voxel_size().prod(); }
  /// Grey extinction σt = σa + σs of voxel v (channel 0; validate_medium checks greyness).
  double sigma_t(std::int32_t v) const { return sigma_a(v, 0) + sigma_s(v, 0); }
  /// Index of voxel (x, y, z).
  std::int32_t index(int x, int y, int z) const {
    return x + resolution.x() * (y + resolution.y() * z);
  }
  /// Lower corner of voxel v.
  Eigen::Vector3d voxel_lo(std::int32_t v) const {
    const int x = v % resolution.x(), y = (v / resolution.x()) % resolution.y(),
              z = v / (resolution.x() * resolution.y());
    return lo + voxel_size().cwiseProduct(Eigen::Vector3d(x, y, z));
  }
};

/// Voxels per axis for a box: `voxels` along its longest axis (the others in proportion, at
/// least 1), or cubes of edge about `voxel_size` (ceil(extent / size) per axis) when
/// voxel_size > 0. Throws UsageError for a result above kMaxMediumVoxels.
Eigen::Vector3i medium_resolution(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int voxels,
                                  double voxel_size);

/// The largest voxel count a medium may have: 2^22 (128³ is 2^21): beyond that the zone
/// rows of F (a few hundred entries each) no longer fit a workstation's memory.
constexpr std::int64_t kMaxMediumVoxels = std::int64_t{1} << 22;

/// A homogeneous medium over [lo, hi] split into `resolution` voxels.
Medium homogeneous_medium(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                          const Eigen::Vector3i& resolution, const Eigen::Vector3d& sigma_a,
                          const Eigen::Vector3d& sigma_s, const Eigen::Vector3d& emission);

/// Checks a medium; throws UsageError naming `what` (an option or a file) when the box is
/// empty or inverted, a coefficient is negative or not finite, σt is coloured (differs
/// between channels by more than 1e-12 relative: rounding of a sum, far below any physical
/// difference), or a voxel emits without extinction (emission needs σt > 0).
void validate_medium(const Medium& medium, const std::string& what);

/// A hash of what the exchange factors depend on: the box, the resolution and every voxel's
/// extinction σt (bit patterns). Albedo and emission are left out: they enter the system as
/// the zones' ρ and E, not F, so a saved F serves any of them (like a surface's colour).
std::uint64_t extinction_hash(const Medium& medium);

/// Visits, in order along the ray o + t d (d unit), every voxel the part t ∈ [t0, t1] crosses
/// with positive length: visit(voxel, t_enter, t_exit). Nothing when the segment misses the
/// box. Each crossing's parameters come from the voxel planes directly (not accumulated), so
/// their error is a few ulps of the coordinates. O(voxels crossed).
template <class Visit>
void traverse_medium(const Medium& m, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0,
                     double t1, Visit&& visit) {
  if (m.voxels() == 0) return;
  for (int a = 0; a < 3; ++a) {  // clip to the box (slabs)
    if (d[a] == 0.0) {
      if (o[a] < m.lo[a] || o[a] > m.hi[a]) return;
      continue;
    }
    double ta = (m.lo[a] - o[a]) / d[a], tb = (m.hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (!(t0 < t1)) return;
  const Eigen::Vector3d h = m.voxel_size();
  const Eigen::Vector3d start = o + 0.5 * (t0 + std::min(t1, t0 + 1e-9 * h.minCoeff())) * d;
  Eigen::Vector3i cell, step;
  Eigen::Vector3d t_next;
  for (int a = 0; a < 3; ++a) {
    cell[a] = std::clamp(static_cast<int>(std::floor((start[a] - m.lo[a]) / h[a])), 0,
                         m.resolution[a] - 1);
    step[a] = d[a] > 0.0 ? 1 : -1;
  }
  const auto plane_t = [&](int a) {
    if (d[a] == 0.0) return std::numeric_limits<double>::infinity();
    const double plane = m.lo[a] + (cell[a] + (step[a] > 0 ? 1 : 0)) * h[a];
    return (plane - o[a]) / d[a];
  };
  for (int a = 0; a < 3; ++a) t_next[a] = plane_t(a);
  double t = t0;
  while (true) {
    int a = 0;
    if (t_next[1] < t_next[a]) a = 1;
    if (t_next[2] < t_next[a]) a = 2;
    const double t_exit = std::min(t_next[a], t1);
    if (t_exit > t) visit(m.index(cell.x(), cell.y(), cell.z()), t, t_exit);
    if (t_exit >= t1) return;
    t = std::max(t, t_exit);
    cell[a] += step[a];
    if (cell[a] < 0 || cell[a] >= m.resolution[a]) return;
    t_next[a] = plane_t(a);
  }
}

/// Optical depth τ = ∫ σt ds of the segment o + t d, t ∈ [t0, t1] (d unit): exact up to
/// rounding (see above). O(voxels crossed).
double optical_depth(const Medium& medium, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                     double t0, double t1);

/// exp(−τ) of the segment from a to b.
double transmittance(const Medium& medium, const Eigen::Vector3d& a, const Eigen::Vector3d& b);

}  // namespace lambert
