#pragma once
// Adaptive meshing: per-patch error estimates from a solution, and conforming refinement of
// the worst patches by longest-edge bisection (Rivara's LEPP algorithm: a triangle is
// bisected at its longest edge's midpoint together with the neighbours sharing that edge,
// after their own longest-edge propagation, so no T-vertex is ever created within a
// surface; angles stay bounded below by half the initial mesh's smallest angle).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "geometry/mesh/mesh.hpp"
#include "geometry/scene.hpp"

namespace lambert {

/// The mesh with every quad split into two triangles along its shorter diagonal (triangles
/// are copied); origin[i] is the patch of `mesh` new patch i comes from.
struct RefinedMesh {
  PatchMesh mesh;
  std::vector<std::int32_t> origin;  ///< the old patch each new patch lies in
  std::vector<char> changed;         ///< 1 when new patch i is not an old patch as it was
};
RefinedMesh triangulate_quads(const PatchMesh& mesh);

/// Per-patch error estimate of a piecewise-constant solution B (N x 3): the patch's area
/// times the largest jump of its mean radiosity (RGB average) to a neighbour sharing an
/// edge within its surface, halved (the constant's error against a field that varies that
/// much across the patch): e_i = A_i max_j |b_i - b_j| / 2 (W, scene units). Isolated
/// patches get 0. O(N).
std::vector<double> patch_errors(const PatchMesh& mesh, const Eigen::MatrixX3d& B);

/// Per-patch error estimate of the shaded field (vertex_field.hpp's LinearFit interpolation
/// of B, the Gouraud field `run` renders on an adapted mesh) on a triangle mesh: the
/// patch's area times the difference between its constant and the field's mean over it,
///   e_i = A_i |b_i - (f(a) + f(b) + f(c)) / 3|   (RGB means; W, scene units).
/// The interpolation reproduces a linear B, so e_i measures what it misses, the curvature
/// and the kinks inside the patch (O(A h² |B''|)), not the slope (patch_errors' jumps are
/// O(h |∇B|) where a linear interpolant is already exact). O(N).
std::vector<double> field_patch_errors(const PatchMesh& mesh, const Eigen::MatrixX3d& B);

/// Per-patch error estimate of a field with exact direct light at the vertices
/// (exact_direct_vertex_field): its direct part is the linear interpolant of H_d between the
/// corners, so the patch's error is estimated from H_d at its edge midpoints,
///   e_i = A_i ρ̄_i max_edges |H_d(m) - (H_d(a) + H_d(b)) / 2|   (RGB means; W, scene units),
/// the interpolation error where it is largest for a quadratic (exact for one), plus the
/// jump estimate of patch_errors applied to the reflected indirect light ρ_i I_i
/// (`indirect`, N x 3, as in exact_direct_vertex_field). Where the edges follow the shadow
/// lines (discontinuity meshing) this marks the curved parts of the penumbrae, not the
/// kinks the mesh already resolves. Cost: 2 exact evaluations (direct_light.hpp) per patch
/// corner; parallel over `threads`, deterministic.
std::vector<double> exact_direct_patch_errors(const Scene& scene, const PatchMesh& mesh,
                                              const Eigen::MatrixX3d& indirect, int threads = 0);

/// Bisects the `marked` triangles (and whatever conformity requires) once each. Every patch
/// must be a triangle (triangulate_quads). Children keep their parent's reflectance,
/// emission and surface; `origin` maps to the parent's index. Deterministic.
RefinedMesh refine_marked(const PatchMesh& mesh, const std::vector<char>& marked);

}  // namespace lambert
