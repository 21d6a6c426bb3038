#pragma once
// PLY output of the patch mesh with per-vertex colours, for MeshLab, Blender and friends.
//
// ASCII PLY 1.0. One PLY vertex per shading vertex of a VertexField (so creases and surface
// borders keep their own colours): float x y z, float nx ny nz, uchar red green blue, float
// radiosity_r radiosity_g radiosity_b. Colours are the radiance L = B/π tone-mapped exactly
// like the PNG preview (exposure 2^EV, clip, sRGB OETF; see io/tonemap.hpp) with the EV
// stated in a header comment; radiosity_* carry the linear B (units of the scene's E).
// Faces: one per patch (triangles and quads), wound like the patch (front = CCW).

#include <string>

#include "geometry/mesh.hpp"
#include "geometry/vertex_field.hpp"

namespace lambert {

/// Writes `field` on `mesh` as a coloured PLY with exposure `ev` (stops), atomically.
/// `comment` (one line) is added to the header. Throws IoError.
void write_ply(const std::string& path, const PatchMesh& mesh, const VertexField& field, double ev,
               const std::string& comment = "");

}  // namespace lambert
