#pragma once
// Meshing: subdivision of every surface into patches (triangles and quads), conforming
// within a surface (shared vertices, no T-junctions created by the mesher), preserving
// area exactly (sub-elements tile each planar element).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "geometry/scene.hpp"

namespace lambert {

/// The key of the undirected edge between vertices a and b (the same for (b, a)).
inline std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

/// One radiosity element: a planar triangle (vertex_count 3) or quad (4).
struct Patch {
  std::array<std::int32_t, 4> vertices{};  ///< into PatchMesh::vertices; [3] unused for triangles
  int vertex_count = 3;
  double area = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();    ///< unit front normal (winding)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< area centroid
  Eigen::Vector3d rho = Eigen::Vector3d::Zero();  ///< its face's Face::rho, else its material's
  Eigen::Vector3d emission = Eigen::Vector3d::Zero();  ///< emitted radiosity E (W/m^2)
  std::int32_t surface = 0;                            ///< index into Scene::surfaces
};

/// The patches of a scene. Vertices are shared within a surface, never across surfaces.
struct PatchMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::int32_t> vertex_surface;  ///< surface of each vertex
  std::vector<Patch> patches;
  std::vector<std::string> surface_names;  ///< copied from the scene, indexed by surface id
  /// Specular part of each surface's material (indexed by surface id); empty when no
  /// surface is specular (every mesh of a purely diffuse scene).
  std::vector<Specular> surface_specular;
  double scale = 1.0;     ///< bounding-box diagonal (for relative epsilons)
  double max_edge = 0.0;  ///< edge bound used (0 = one element per face)

  std::int32_t size() const { return static_cast<std::int32_t>(patches.size()); }
  /// True when some surface is specular (rays continue at it).
  bool has_specular() const { return !surface_specular.empty(); }
  /// The specular part of patch i's surface (nullptr when it is purely diffuse).
  const Specular* specular_of(std::int32_t i) const {
    if (surface_specular.empty()) return nullptr;
    const Specular& s = surface_specular[patches[i].surface];
    return s.any() ? &s : nullptr;
  }
  /// Corner positions of patch i.
  std::vector<Eigen::Vector3d> corners(std::int32_t i) const;
};

/// Largest mesh lambert builds (F would need ~1e16 entries beyond it anyway).
constexpr std::int64_t kMaxPatches = 100000000;

/// Patches every surface gets at least under a patch target (MeshOptions::surface_floor).
constexpr int kDefaultSurfaceFloor = 4;

/// Meshing target. Exactly one of max_edge > 0 or target_patches > 0 is used
/// (max_edge wins when both are set); with neither, every face becomes one element.
struct MeshOptions {
  double max_edge = 0.0;            ///< longest allowed patch edge, scene units
  std::int64_t target_patches = 0;  ///< approximate total patch count
  /// With a patch target (and not discontinuity meshing): every surface gets at least this
  /// many patches (a finer edge bound of its own where the scene's leaves it fewer), the
  /// floors taking at most a quarter of the target: when more surfaces would need them, the
  /// largest by area get them. 0 or 1: no floor.
  int surface_floor = kDefaultSurfaceFloor;
  /// Discontinuity meshing (discontinuity.hpp): constrained Delaunay triangles whose edges
  /// follow the D0 and D1/D2 lines of the emitters (and of the `discontinuity_sources`
  /// brightest other surfaces), instead of the uniform subdivision.
  bool discontinuity = false;
  int discontinuity_sources = 0;
  int threads = 0;  ///< for the discontinuity lines' visibility rays (0 = all cores)
};

/// The work of a plan's search for the edge bound (for tests and benchmarks).
struct MeshPlanStats {
  std::int64_t evaluations = 0;  ///< whole-scene patch counts evaluated (one per trial edge)
  std::int64_t terms = 0;  ///< terms summed by those evaluations (edge classes and their products)
};

/// What mesh_scene will build, computed without building it (O(faces log faces) once, then
/// O(surfaces + edge classes) per trial edge).
struct MeshPlan {
  double max_edge = 0.0;     ///< the edge bound mesh_scene will use
  std::int64_t patches = 0;  ///< the exact patch count it will produce
  /// Per surface, its own edge bound where the floor (MeshOptions::surface_floor) made it
  /// finer than max_edge; empty when every surface uses max_edge.
  std::vector<double> surface_edge;
  std::int32_t floored = 0;  ///< surfaces the floor raised
  /// For a patch target: a line for the log when the mesh exceeds the target by more than
  /// 10 % (detail that keeps a patch per face), naming the largest such surface; else "".
  std::string note;
  /// A line for the log when the floor raised some surfaces (how many, the patches it
  /// added, and when capped how many surfaces it covered); else "".
  std::string floor_note;
  MeshPlanStats stats;  ///< what the search cost
};
/// The edge bound and patch count mesh_scene(scene, options) will use and produce.
MeshPlan plan_mesh(const Scene& scene, const MeshOptions& options);
/// Approximate peak memory (bytes) of a mesh of `patches` patches and its BVH.
double mesh_peak_bytes(std::int64_t patches);

/// Copies the scene's surface names (and specular parts, when any) into an empty mesh.
void copy_surfaces(const Scene& scene, PatchMesh& mesh);

/// Subdivides every surface of `scene`. Faces with more than 4 vertices and concave quads
/// are triangulated first. Each element edge of length L shared within a surface gets
/// n = ceil(L / max_edge) segments, raised until every triangle has equal counts on its
/// three edges and every quad on opposite edges (a monotone fixpoint), so neighbours agree.
/// Throws UsageError if the mesh would exceed kMaxPatches. Complexity O(faces + patches).
/// With options.discontinuity, every surface is meshed by mesh_scene_constrained with the
/// edge bound planned as above (for a patch target, corrected once by the ratio of the
/// patches made to the target: the target is met approximately).
PatchMesh mesh_scene(const Scene& scene, const MeshOptions& options);

/// A patch over mesh vertices v[0..n) (n = 3 or 4, counter-clockwise about the front
/// normal): its area, unit normal and area centroid; rho, emission and surface are left to
/// the caller.
Patch make_patch(const PatchMesh& mesh, std::array<std::int32_t, 4> v, int n);

/// A stable 64-bit hash of the meshed geometry (vertices, patches, surfaces) and of the
/// specular parts (extended form factors follow rays through them), which is all F depends
/// on; diffuse reflectance and emission may change without invalidating a saved F.
std::uint64_t mesh_hash(const PatchMesh& mesh);

}  // namespace lambert
