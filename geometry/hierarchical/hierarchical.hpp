#pragma once
// Hierarchical radiosity with volume clustering (Hanrahan, Salzman & Aupperle 1991; Smits,
// Arvo & Greenberg 1994; Sillion 1995): the `hierarchical` method. It never builds F.
//
// The hierarchy. Every input face (after the mesher's triangulation of polygons with more
// than four corners and of concave quads: mesh_scene with no edge bound) is a root element,
// split on demand into 4 (triangles: 4 similar triangles through the edge midpoints; quads:
// 4 quads through the edge midpoints and the centre) while a child would keep at least
// `min_area`. Above the faces, a binary cluster tree built bottom-up over the faces' bounding
// boxes (median splits along the longest axis, deterministic).
//
// Links. A link p <- q carries the area-averaged factor F_pq (H_p += F_pq B_q, H the
// irradiance, W/m^2) and its error per unit source radiosity. Element-element links use the
// exact point-to-patch factor at 2x2 Gauss points of p times the visible fraction from
// kernel-sampled Embree rays (the hybrid kernel on element geometry); links that involve a
// cluster use the isotropic conservative bound min(A_p A_q / (π d^2), A_p, A_q) (d the
// distance of the bounding boxes) and an area-sampled Monte Carlo estimate of the transfer,
// handed to a receiving cluster's faces by their orientation (links.hpp). The
// refinement oracle (BF refinement against the current B) refines a link while
// max_c B_q,c x err_pq > epsilon x (total emitted power, max channel).
//
// Solution. Jacobi sweeps: gather over links, push (irradiance down) - pull (area-averaged
// radiosity up), until the largest change of a leaf's B relative to the largest leaf B is
// <= tol; refinement is interleaved with the solution (refine, solve, refine against the new
// B, ... until a pass refines nothing).
//
// Threads and determinism: refinement rounds and gathers run in parallel over links and
// receivers; nodes are created serially in a fixed order and every ray stream is seeded from
// (seed, link), so a fixed seed gives bitwise identical results for any thread count.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/mesh/mesh.hpp"
#include "geometry/scene.hpp"

namespace lambert {

/// Settings of a hierarchical solve.
struct HierarchicalOptions {
  double epsilon = 1e-5;   ///< link power-error bound, as a fraction of the emitted power
  double min_area = 0.0;   ///< smallest element area (scene units^2); 0 = total area x 1e-5
  int link_rays = 16;      ///< visibility rays per element link (samples per cluster link)
  double tol = 1e-6;       ///< stopping rule of the Jacobi sweeps (relative change of B)
  int max_iterations = 1000;  ///< sweeps per refinement pass
  int max_passes = 10;        ///< refinement passes (refine, solve) at most
  std::uint64_t seed = 1;
  int threads = 0;          ///< 0 = all cores
  bool progress = false;    ///< progress lines on stderr
  double memory_limit = 0;  ///< bytes the hierarchy may use (0 = no limit): exceeding it throws
};

/// Power bookkeeping of a hierarchical solution, per channel (W in scene units).
struct HierarchicalEnergy {
  double emitted = 0.0;   ///< sum over leaves of A E
  double absorbed = 0.0;  ///< sum over leaves of A (1 - rho) H
  double escaped = 0.0;   ///< power sent (sum A B) minus power received over links (sum A H)
  double relative_imbalance = 0.0;  ///< |emitted - absorbed - escaped| / emitted
};

/// What a hierarchical solve did.
struct HierarchicalStats {
  std::int64_t faces = 0;     ///< root elements
  std::int64_t elements = 0;  ///< element nodes (roots and their descendants)
  std::int64_t clusters = 0;  ///< cluster nodes
  std::int64_t leaves = 0;    ///< leaf elements (the output patches)
  std::int64_t links = 0;     ///< links at the end
  std::int64_t cluster_links = 0;  ///< links with a cluster at one end
  std::int64_t rays = 0;      ///< visibility rays traced
  int passes = 0;             ///< refinement passes
  int iterations = 0;         ///< Jacobi sweeps in all passes
  bool converged = false;     ///< the last pass's sweeps met tol
  double change = 0.0;        ///< the last sweep's relative change
  double memory_bytes = 0.0;  ///< nodes + links + BVH at the end
  double min_area = 0.0;      ///< the element area bound used
  double build_seconds = 0.0, refine_seconds = 0.0, solve_seconds = 0.0;
  std::array<HierarchicalEnergy, 3> energy;
  /// Emitting surfaces none of whose faces can exchange light with any other face (each
  /// behind the other's plane): their light leaves the scene unseen (inverted winding?).
  /// Checked for at most kBlindCheckPairs face pairs (beyond that none are listed).
  std::vector<std::int32_t> blind_emitters;
};

/// Face pairs the blind-emitter check examines at most (emitting faces x faces, each pair a
/// few dot products: ~0.1 s).
constexpr std::int64_t kBlindCheckPairs = 100000000;

/// The leaves as a patch mesh (vertices shared within a surface by exact position; hanging
/// vertices where neighbours were split to different depths) and their radiosity.
struct HierarchicalResult {
  PatchMesh mesh;
  Eigen::MatrixX3d B;  ///< leaves x 3
  /// Per leaf: the oracle's bound on |B - B_exact| from the transfers of the final links
  /// (max over channels): rho x (sum over the links at the leaf and its ancestors of each
  /// link's power error / its receiver's area). One bounce: interreflection can amplify it
  /// by up to 1 / (1 - rho_max).
  Eigen::VectorXd error_bound;
  HierarchicalStats stats;
};

/// Solves the scene's radiosity hierarchically. Throws UsageError for bad options and
/// Error when the hierarchy would exceed options.memory_limit.
HierarchicalResult solve_hierarchical(const Scene& scene, const HierarchicalOptions& options);

}  // namespace lambert
