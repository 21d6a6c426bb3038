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
// area-weighted mean of the patch centroids is the vertex itself.
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
// meet at a vertex; the error is small (2e-5 on the Cornell box) but not bounded by
// rounding. The default (Conservative) therefore rescales each surface and channel by
// s = sum_i A_i b_i / ∫ f dA, which makes power conservation exact up to rounding (relative
// error <= kPowerTolerance), keeps f >= 0 and reproduces a constant field exactly.
//
// Complexity O(patches + vertices); single-threaded pure functions of their inputs.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/mesh.hpp"

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
  Conservative   ///< AreaWeighted, then rescaled per surface and channel to conserve power
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

/// Reconstructs per-vertex values of `patch_values` (N x 3) on the shading vertices. When
/// `power` is given, it receives one entry per surface (indexed by surface id).
VertexField interpolate_to_vertices(const PatchMesh& mesh, const Eigen::MatrixX3d& patch_values,
                                    VertexInterpolation mode = VertexInterpolation::Conservative,
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

}  // namespace lambert
