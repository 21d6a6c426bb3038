#pragma once
// Per-vertex reconstruction of a per-patch field (radiosity B, N x 3) for Gouraud shading,
// vertex EXR and PLY output.
//
// Shading vertices. A PatchMesh vertex is shared by the patches of one surface (never across
// surfaces), but a surface may fold (the faces of a block are one surface). Values must not
// blend across surfaces, materials or creases, so each mesh vertex is split into one shading
// vertex per smoothing group: the patches around it, within its surface, whose normals are
// within kCreaseAngleDegrees of each other. A block corner thus gets three shading vertices,
// a vertex inside a wall one.
//
// Interpolation. The value at shading vertex k is the area-weighted mean of the patch values
// around it:  v_k = sum_{i ∋ k} A_i b_i / sum_{i ∋ k} A_i.  A constant field is reproduced
// exactly; a linear field is reproduced exactly at interior vertices whose neighbourhood is
// point-symmetric (uniform grids, the mesher's similar-triangle subdivision), since then the
// area-weighted mean of the patch centroids is the vertex itself. Elsewhere (a graded mesh
// from --adapt, where a large patch beside small ones pulls the mean by O(H |∇B|)), LinearFit
// (`--vertex-interp linear`, auto's choice on an --adapt mesh) takes the local linear fit
// instead, then rescales like Conservative: weighted least squares
// b_i ≈ a + g · (c_i - x_k) over the patches around the vertex (weights A_i), v_k = a clamped
// to the range of their b_i. It is the area-weighted mean wherever the neighbourhood is
// point-symmetric (the centroids' weighted mean is x_k: a does not depend on g), exact for a
// linear field wherever the centroids span the plane, and the mean where they do not (a
// vertex on a surface's edge between two quads, a corner). It is not linear in b (the clamp,
// and a rescale that is no longer ~1): the viewer's relighting by bases is exact for the others.
//
// Power. Linear interpolation on triangles and bilinear interpolation on quads define a
// continuous field f on each surface. Its integral is computed exactly (triangles:
// A (v0 + v1 + v2) / 3; quads: 2 x 2 Gauss-Legendre in (u, v), exact because f |J| has
// degree <= 3 in each of u and v, f being bilinear and the Jacobian |J| linear for a planar
// quad). Area-weighted averaging is already exactly conservative on triangles and
// parallelogram quads: ∫ f dA = sum_k v_k m_k with the lumped mass m_k = sum_{i ∋ k} A_i / c
// (c corners, each hat function integrating to A_i / c there), so ∫ f dA = sum_k sum_{i ∋ k}
// A_i b_i / c = sum_i A_i b_i. It is not where a quad is not a parallelogram (its corner
// masses differ from A/4: the Cornell floor is a trapezoid) or where triangles and quads
// meet at a vertex (the error is small, 2e-5 on the Cornell box, but not bounded by
// rounding), nor once hanging vertices (below) are anchored (larger: a coarse edge's values
// replace the fine patches' means). The default (Conservative) therefore rescales each
// surface and channel by s = sum_i A_i b_i / ∫ f dA, which makes power conservation exact up
// to rounding (relative error <= kPowerTolerance), keeps f >= 0 and reproduces a constant
// field exactly.
//
// Hanging vertices. A non-conforming mesh (the leaves of the hierarchical method: elements
// split into 4 through their edge midpoints 0.5 (a + b) to different depths) has vertices h
// inside an edge (a, b) of a coarser patch P. P interpolates linearly between a and b along
// that edge, so the value at h must be v_h = (1 - t) v_a + t v_b with h = (1 - t) x_a + t x_b,
// v_a and v_b being P's own corner values (patch_corners of P); otherwise the field cracks
// along the edge. Every shading vertex at h whose smoothing group is compatible with P (same
// surface, group normal within kCreaseAngleDegrees of P's normal) is anchored so, after the
// area-weighted mean and before the integral and the rescale (a uniform per-surface scale
// keeps the field continuous). The rule is unchanged on a conforming mesh (none are found).
//
// Detection is exact for midpoint subdivision: for each patch edge (a, b) the midpoint
// m = 0.5 (a + b) is looked up by exact position among the shading vertices of P's surface
// (a hash table); when found (t = 1/2), the halves (a, m) and (m, b) are searched the same
// way (t = 1/4, 3/4, ...), until a midpoint is not a vertex. Limits: a vertex on an edge at
// a non-dyadic position, or whose coordinates were not computed by repeated 0.5 (a + b) from
// that edge's ends (other subdivision rules, most T-junctions of the input), is not found and
// keeps its area-weighted value (and its crack). A shading vertex found on several coarse
// edges (non-manifold surfaces) is anchored to the first (patch order).
//
// Chains: the ends a, b may themselves be anchored (h on a fine edge whose end hangs on a
// coarser edge), so anchors are applied in dependency order (Kahn's topological sort: an
// anchor after the anchors of its ends). Edge length is not a valid order (a fine element's
// long edge may end at a vertex hanging on a short coarse edge). Midpoint subdivision of
// faces that meet edge to edge creates no dependency cycle: the uniform subdivision to any
// depth d is conforming, so a vertex inside an edge of a depth-d element first appears deeper
// than d, while that element's corners appear at depth <= d. T-junctions in the input can
// (a pinwheel of rectangles): the sort then drops the first anchor left on the cycle (its
// vertex keeps its area-weighted value, the crack stays there) and goes on, so it always
// terminates.
//
// Complexity O(patches + vertices) (the detection: one expected-O(1) lookup per patch edge
// and two per hanging vertex found); single-threaded pure functions of their inputs.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/mesh/mesh.hpp"
#include "geometry/scene.hpp"

namespace lambert {

/// Patch normals further apart than this angle do not share a shading vertex (a crease). 30°
/// is the usual auto-smooth angle: it splits box corners (90°) and keeps nearly coplanar
/// pieces (the Cornell red wall is two triangles 0.1° apart) smooth.
constexpr double kCreaseAngleDegrees = 30.0;

/// Relative power error allowed after the conservative rescale: the integral and the patch
/// sum are both sums of <= ~1e6 positive terms in double precision, each within n·eps
/// (n·2.2e-16 <= 2.2e-10 for n = 1e6), so 1e-9 leaves margin and still flags real bugs.
constexpr double kPowerTolerance = 1e-9;

/// How per-vertex values are reconstructed from per-patch values.
enum class VertexInterpolation {
  AreaWeighted,  ///< area-weighted mean of the patches around each shading vertex
  Conservative,  ///< AreaWeighted, then rescaled per surface and channel to conserve power
  LinearFit      ///< the local linear fit of the patches around each vertex, rescaled likewise
};

/// Parses "area" or "conservative"; throws UsageError otherwise.
VertexInterpolation parse_vertex_interpolation(const std::string& name);
/// "area" or "conservative".
const char* to_string(VertexInterpolation mode);

/// Shading vertices of a PatchMesh and the values reconstructed on them.
struct VertexField {
  std::vector<Eigen::Vector3d> positions;  ///< per shading vertex
  std::vector<Eigen::Vector3d> normals;    ///< area-weighted unit normal of its smoothing group
  std::vector<std::int32_t> surface;       ///< surface index of each shading vertex
  std::vector<std::int32_t> mesh_vertex;   ///< the PatchMesh vertex it sits on
  /// Per patch: the shading vertex of each corner ([3] unused for triangles).
  std::vector<std::array<std::int32_t, 4>> patch_corners;
  Eigen::MatrixX3d values;  ///< per shading vertex, same units as the patch field

  /// Number of shading vertices.
  std::int32_t size() const { return static_cast<std::int32_t>(positions.size()); }
};

/// Power of one surface: patch sum vs the integral of the reconstructed field.
struct SurfacePower {
  std::string name;
  double area = 0.0;
  Eigen::Vector3d patch_power = Eigen::Vector3d::Zero();          ///< sum_i A_i b_i per channel
  Eigen::Vector3d field_power = Eigen::Vector3d::Zero();          ///< ∫ f dA per channel (exact)
  Eigen::Vector3d area_weighted_power = Eigen::Vector3d::Zero();  ///< ∫ f dA before rescale
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();  ///< rescale applied (1 for AreaWeighted)

  /// max over channels of |field - patch| / patch (0 where patch power is 0).
  double relative_error() const;
  /// The same for the area-weighted field before any rescale.
  double area_weighted_relative_error() const;
};

/// Builds the shading vertices of `mesh` (splitting at surfaces and creases); values empty.
VertexField build_shading_vertices(const PatchMesh& mesh);

/// A shading vertex tied to an edge of a coarser patch: v_vertex = (1 - t) v_a + t v_b.
struct HangingVertex {
  std::int32_t vertex = -1;  ///< the shading vertex at h
  std::int32_t a = -1;       ///< the coarse patch's shading vertex at the first end
  std::int32_t b = -1;       ///< the same for the second end
  double t = 0.5;            ///< h = (1 - t) x_a + t x_b, a dyadic fraction in (0, 1)
  std::int32_t patch = -1;   ///< the coarse patch whose edge (a, b) holds h
};

/// The hanging vertices of `field`'s shading vertices on `mesh` (the rule above), in an
/// order where every anchor comes after the anchors of its ends. Empty on a conforming mesh.
std::vector<HangingVertex> find_hanging_vertices(const PatchMesh& mesh, const VertexField& field);

/// Sets field.values at each hanging vertex from its ends, in the given order.
void anchor_hanging_vertices(const std::vector<HangingVertex>& hanging, VertexField& field);

/// Reconstructs per-vertex values of `patch_values` (N x 3) on the shading vertices (the
/// area-weighted mean, hanging vertices anchored, then the rescale if Conservative). When
/// `power` is given, it receives one entry per surface (indexed by surface id).
VertexField interpolate_to_vertices(const PatchMesh& mesh, const Eigen::MatrixX3d& patch_values,
                                    VertexInterpolation mode = VertexInterpolation::Conservative,
                                    std::vector<SurfacePower>* power = nullptr);

/// Per-vertex radiosity with exact direct light (direct_light.hpp), for meshes whose
/// edges follow the shadow boundaries (discontinuity meshing): splitting each patch's
/// B_i = E_i + ρ_i (D_i + I_i) into emission, direct irradiance D_i = Σ_j F_ij E_j and
/// indirect irradiance I_i = Σ_j F_ij (B_j - E_j) (`indirect`, N x 3, from the F B was solved
/// with), the value at shading vertex k is
///   v_k = Ē_k + ρ̄_k (H_d(x_k) + Ī_k),
/// Ē, ρ̄, Ī the area-weighted means over its patches and H_d the exact direct irradiance at
/// its position and normal. The direct part, where the radiosity has its kinks and jumps,
/// is then exact at every vertex (no Monte Carlo noise, no mixing of the two sides of a
/// penumbra boundary); only the smoother indirect part is averaged. No rescale: `power`
/// (per surface) reports how far the field's integral is from Σ A_i B_i (the patches'
/// discretisation and estimator error, not a reconstruction defect). Cost: one exact
/// shadow evaluation per shading vertex and emitter face (direct_light.hpp).
VertexField exact_direct_vertex_field(const Scene& scene, const PatchMesh& mesh,
                                      const Eigen::MatrixX3d& patch_values,
                                      const Eigen::MatrixX3d& indirect, int threads = 0,
                                      std::vector<SurfacePower>* power = nullptr);

/// Exact integral over patch i of the field interpolated from `values` (linear on
/// triangles, bilinear on quads), per channel.
Eigen::Vector3d integrate_patch(const PatchMesh& mesh, const VertexField& field, std::int32_t i);

/// Per-surface power of `patch_values` and of `field` (patch_power, field_power, area).
std::vector<SurfacePower> surface_power(const PatchMesh& mesh, const Eigen::MatrixX3d& patch_values,
                                        const VertexField& field);

/// Interpolation weights of a point inside patch i: barycentric (triangles, weights for
/// corners 0..2) or bilinear (quads, corners 0..3) from the position `p` on the patch plane.
/// Points slightly outside (ray-hit rounding) are clamped onto the patch.
std::array<double, 4> patch_weights(const PatchMesh& mesh, std::int32_t i,
                                    const Eigen::Vector3d& p);

/// The field's value (RGB) at point p of patch i: its corners' values with patch_weights.
Eigen::Vector3d field_value(const PatchMesh& mesh, const VertexField& field, std::int32_t i,
                            const Eigen::Vector3d& p);

}  // namespace lambert
