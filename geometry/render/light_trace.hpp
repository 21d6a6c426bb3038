#pragma once
// Per-surface mean radiosity by light tracing: photons leave the emitters and bounce off the
// diffuse surfaces until absorbed or escaped, and each surface's reflected power is counted
// where it lands. No F, no solve and no discretisation of the radiosity (the mesh only names
// the surfaces and carries the geometry): an independent reference for the matrix and
// hierarchical methods' per-surface averages (bench/hierarchical_bench).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/mesh/mesh.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert {

/// One surface's mean radiosity and its standard error.
struct TracedSurface {
  std::string name;
  double area = 0.0;
  Eigen::Vector3d average = Eigen::Vector3d::Zero();  ///< E + reflected power / area (W/m^2)
  Eigen::Vector3d stderr_ = Eigen::Vector3d::Zero();  ///< of `average`, from 64 batches
};

struct LightTraceResult {
  std::vector<TracedSurface> surfaces;                ///< indexed by surface id
  Eigen::Vector3d escaped = Eigen::Vector3d::Zero();  ///< fraction of the emitted power
  std::int64_t photons = 0, rays = 0;
  std::int64_t capped = 0;  ///< photon paths cut at the bounce cap (reflectance near 1)
};

/// Traces `photons` photons (at least 64) from the emitting patches of `mesh` (chosen in
/// proportion to A E summed over channels, uniform on the patch, cosine-distributed), with
/// Russian roulette on each bounce's largest reflectance; a photon that lands on the back of
/// a patch is absorbed there, as F counts only front-facing pairs. Deterministic: 64 batches,
/// each its own stream of (seed, batch), summed in batch order, so the result is bitwise the
/// same for any thread count; the standard errors come from the batches' spread. Throws
/// UsageError when nothing emits.
LightTraceResult light_trace(const PatchMesh& mesh, const Bvh& bvh, std::int64_t photons,
                             std::uint64_t seed, int threads);

}  // namespace lambert
