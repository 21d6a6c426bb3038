#include "geometry/media/medium.hpp"

#include <cstring>
#include <sstream>

#include "core/error.hpp"
#include "core/sampling.hpp"

namespace lambert {

Eigen::Vector3i medium_resolution(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int voxels,
                                  double voxel_size) {
  const Eigen::Vector3d extent = hi - lo;
  Eigen::Vector3i r;
  const double size = voxel_size > 0.0 ? voxel_size : extent.maxCoeff() / std::max(voxels, 1);
  for (int a = 0; a < 3; ++a) {
    const double n = std::ceil(extent[a] / size - 1e-9);  // 1e-9: an exact multiple stays
    if (!(n < 1e7)) throw UsageError("--voxel-size is too small for the medium box");
    r[a] = std::max(1, static_cast<int>(n));
  }
  if (static_cast<std::int64_t>(r.x()) * r.y() * r.z() > kMaxMediumVoxels)
    throw UsageError("the medium would have " +
                     std::to_string(std::int64_t{r.x()} * r.y() * r.z()) + " voxels, more than " +
                     std::to_string(kMaxMediumVoxels) +
                     ": use fewer --voxels or a larger --voxel-size");
  return r;
}

Medium homogeneous_medium(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                          const Eigen::Vector3i& resolution, const Eigen::Vector3d& sigma_a,
                          const Eigen::Vector3d& sigma_s, const Eigen::Vector3d& emission) {
  Medium m;
  m.lo = lo;
  m.hi = hi;
  m.resolution = resolution;
  const std::int32_t n = m.voxels();
  m.sigma_a = sigma_a.transpose().replicate(n, 1);
  m.sigma_s = sigma_s.transpose().replicate(n, 1);
  m.emission = emission.transpose().replicate(n, 1);
  return m;
}

void validate_medium(const Medium& m, const std::string& what) {
  if (!m.lo.allFinite() || !m.hi.allFinite() || (m.hi - m.lo).minCoeff() <= 0.0)
    throw UsageError(what +
                     ": the medium box is empty or inverted (need X0 < X1, Y0 < Y1, Z0 < Z1)");
  if (m.resolution.minCoeff() < 1) throw UsageError(what + ": the medium has no voxels");
  const std::int32_t n = m.voxels();
  LAMBERT_CHECK(m.sigma_a.rows() == n && m.sigma_s.rows() == n && m.emission.rows() == n,
                "medium coefficients do not match its voxels");
  const auto check = [&](const Eigen::MatrixX3d& x, const char* name) {
    if (!x.allFinite() || (n > 0 && x.minCoeff() < 0.0))
      throw UsageError(what + ": " + name + " must be finite and >= 0");
  };
  check(m.sigma_a, "sigma_a");
  check(m.sigma_s, "sigma_s");
  check(m.emission, "emission");
  // Optical thickness across the whole box: below 1e-100 a voxel attenuates nothing a double
  // can hold (1 - 1e-100 == 1) while its albedo and emission divide by sigma_t (1e-320 gave
  // NaN energies); above 1e100 every transmittance underflows. 0 means no medium there.
  const double diagonal = (m.hi - m.lo).norm();
  bool extinguishes = false;
  for (std::int32_t v = 0; v < n; ++v) {
    const Eigen::Vector3d t = (m.sigma_a.row(v) + m.sigma_s.row(v)).transpose();
    extinguishes = extinguishes || t.maxCoeff() > 0.0;
    const double depth = t.maxCoeff() * diagonal;
    if (depth != 0.0 && !(depth >= 1e-100 && depth <= 1e100)) {
      std::ostringstream msg;
      msg << what << ": voxel " << v << ": sigma_a + sigma_s = " << t.maxCoeff()
          << " over the box's diagonal " << diagonal << " is an optical thickness of " << depth
          << ", outside [1e-100, 1e100] (0 for no medium)";
      throw UsageError(msg.str());
    }
    if (t.maxCoeff() - t.minCoeff() > 1e-12 * t.maxCoeff())
      throw UsageError(what +
                       ": sigma_a + sigma_s (the extinction) must be the same in every "
                       "channel (voxel " +
                       std::to_string(v) +
                       "); colour goes in the albedo sigma_s / sigma_t and in the emission");
    if (t[0] == 0.0 && m.emission.row(v).maxCoeff() > 0.0)
      throw UsageError(what + ": voxel " + std::to_string(v) +
                       " emits but has sigma_a + sigma_s = 0 (emission needs extinction)");
  }
  // A medium of no extinction anywhere changes no result: the option would be ignored.
  if (!extinguishes)
    throw UsageError(what +
                     ": the medium extinguishes nothing (sigma_a + sigma_s = 0 in every voxel), "
                     "so it would change no result; give a positive --sigma-a or --sigma-s "
                     "(or a grid with extinction), or leave the medium out");
}

std::uint64_t extinction_hash(const Medium& m) {
  std::uint64_t h = mix64(static_cast<std::uint64_t>(m.voxels()));
  const auto add = [&](double x) {
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    h = mix64(h ^ bits);
  };
  for (int a = 0; a < 3; ++a) add(m.lo[a]), add(m.hi[a]), add(m.resolution[a]);
  for (std::int32_t v = 0; v < m.voxels(); ++v) add(m.sigma_t(v));
  return h;
}

double optical_depth(const Medium& medium, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                     double t0, double t1) {
  double tau = 0.0;
  traverse_medium(medium, o, d, t0, t1,
                  [&](std::int32_t v, double a, double b) { tau += medium.sigma_t(v) * (b - a); });
  return tau;
}

double transmittance(const Medium& medium, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double length = (b - a).norm();
  if (length == 0.0) return 1.0;
  return std::exp(-optical_depth(medium, a, (b - a) / length, 0.0, length));
}

}  // namespace lambert
