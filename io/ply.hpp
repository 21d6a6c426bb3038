#pragma once
// PLY output of the patch mesh with per-vertex colours, for MeshLab, Blender and friends.
//
// ASCII PLY 1.0. One PLY vertex per shading vertex of a VertexField (so creases and surface
// borders keep their own colours): float x y z, float nx ny nz, uchar red green blue, float
// radiosity_r radiosity_g radiosity_b. Colours are the radiance L = B/π tone-mapped exactly
// like the PNG preview (exposure 2^EV, clip, sRGB OETF; see io/tonemap.hpp) with the EV
// stated in a header comment; radiosity_* carry the linear B (units of the scene's E).
// Faces: one per patch (triangles and quads), wound like the patch (front = CCW).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/mesh/mesh.hpp"
#include "geometry/render/vertex_field.hpp"

namespace lambert {

/// Writes `field` on `mesh` as a coloured PLY with exposure `ev` (stops), atomically.
/// `comment` (one line) is added to the header. Throws IoError.
void write_ply(const std::string& path, const PatchMesh& mesh, const VertexField& field, double ev,
               const std::string& comment = "");

/// What a PLY carries besides the geometry: per shading vertex an sRGB colour, and the names
/// and meaning of the three float properties holding field.values.
struct PlyValues {
  std::vector<std::array<std::uint8_t, 3>> colours;  ///< per shading vertex
  std::array<std::string, 3> names;                  ///< e.g. radiosity_r, radiosity_g, ...
  std::vector<std::string> comments;                 ///< header comment lines (units, colours)
};
/// Writes `field` on `mesh` with the given colours and value properties, atomically (the
/// radiosity PLY above is this with tone-mapped colours). Throws IoError.
void write_ply_values(const std::string& path, const PatchMesh& mesh, const VertexField& field,
                      const PlyValues& values);

}  // namespace lambert
