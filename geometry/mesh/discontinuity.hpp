#pragma once
// Discontinuity meshing (Heckbert 1992; Lischinski, Tampieri & Greenberg 1992): the lines on
// each receiving surface where the radiosity or its derivatives jump, and a mesh whose
// patch edges follow them.
//
//   D0 lines: where a blocker touches or pierces a receiver (the radiosity itself jumps:
//             the contact shadow under a block). The blocker face's intersection with the
//             receiver's plane.
//   D1/D2 lines: the boundaries of penumbra and umbra, traced by the critical surfaces of
//             visual events between a source polygon and a blocker (the first or second
//             derivative jumps). Both kinds that involve the source are found:
//               VE: a source vertex s and a blocker edge (p, q): the wedge {s + t (y - s),
//                   y on (p, q), t >= 1} meets the receiver's plane in the projection of
//                   (p, q) from s;
//               EV: a source edge (s1, s2) and a blocker vertex p: the wedge of lines
//                   through p and the edge meets the plane in the projection of (s1, s2)
//                   through p.
//             EEE events (three edges, none of the source's: quadric critical surfaces) are
//             left out; with polygonal sources and blockers they bound only penumbra
//             subregions where two blockers overlap.
// Each wedge line is clipped by visibility: it is kept where its critical line (receiver
// point -> event feature -> source feature) is unoccluded by any other face, tested with
// Embree rays on pieces of at most half the edge bound (a piece is kept when its midpoint's
// two half-lines, stopped 1e-3 of their length short of the grazed feature, are free). So
// kept lines lie exactly on the wedge (to rounding) and their ends are placed to within
// half a piece.
//
// Sources: the faces of every emitting surface, and optionally the `secondary_sources`
// non-emitting surfaces that reflect the most direct light (estimated as rho-bar x area x
// the unoccluded direct irradiance at each face's centroid, Lambert's contour formula).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "geometry/mesh/mesh.hpp"
#include "geometry/scene.hpp"

namespace lambert {

/// One discontinuity line on a receiving surface (3-D, on the receiver face's plane).
struct DiscontinuitySegment {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  int order = 0;          ///< 0 = D0 (contact); 1 = D1/D2 (penumbra or umbra boundary)
  std::int32_t face = 0;  ///< the receiving face (index into Scene::faces)
};

/// Settings of discontinuity meshing.
struct DiscontinuityOptions {
  int secondary_sources = 0;  ///< the brightest non-emitting surfaces used as sources too
  double piece = 0.0;         ///< visibility-test piece length (scene units; 0 = 1/64 of the scene)
  int threads = 0;
};

/// The D0 and D1/D2 lines of `scene` on every face, for the sources above. Deterministic.
std::vector<DiscontinuitySegment> discontinuity_segments(const Scene& scene,
                                                         const DiscontinuityOptions& options);

/// The surfaces used as sources (emitters first, then the secondary ones by decreasing
/// estimated reflected power).
std::vector<std::int32_t> discontinuity_sources(const Scene& scene, int secondary_sources);

/// Meshes every surface by a constrained Delaunay triangulation (CGAL, exact predicates) of
/// each of its planes: the face edges and `constraints` are constraint segments, refined
/// (Delaunay_mesher_2) to triangles with edges at most `max_edge` (0: no size bound) and no
/// angle below kMinAngleDegrees except where two constraints meet at a smaller angle. Where
/// faces of one surface meet at a crease, the Steiner points either side placed on the
/// shared edge are inserted on the other side too (fan splits), so the mesh is conforming
/// within each surface. Triangles tile each face exactly (area to rounding).
/// With `limits`: refused (UsageError, naming the surface and the planned count) as soon as
/// the mesh passes limits.max_patches, not after meshing the rest (a CAD part's sliver facets
/// made 2.5 million patches for a target of 2,000 in 10 minutes); limits.warn false keeps the
/// shortfall warnings out of the log (a first pass that is meshed again).
struct ConstrainedLimits {
  std::int64_t max_patches = kMaxPatches;
  std::int64_t planned = 0;  ///< the patches the caller planned, for the refusal's message
  bool warn = true;
};
PatchMesh mesh_scene_constrained(const Scene& scene, double max_edge,
                                 const std::vector<DiscontinuitySegment>& constraints,
                                 const ConstrainedLimits& limits = {});

/// The smallest angle the refinement guarantees away from small constraint angles:
/// arcsin(1 / (2 B)) for CGAL's shape bound B = sqrt(2) (the circumradius-to-shortest-edge
/// ratio), 20.7 degrees, the bound for which Delaunay refinement provably terminates.
constexpr double kMinAngleDegrees = 20.7;

}  // namespace lambert
