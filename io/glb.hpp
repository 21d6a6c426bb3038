#pragma once
// glTF 2.0 binary (.glb) output: one triangle mesh with per-vertex float attributes, an
// optional line mesh over the same vertices (patch edges) and an optional camera, for
// three.js, Blender and any glTF viewer (Khronos glTF 2.0 specification, section 4.4 GLB).
//
// Layout. A 12-byte header ("glTF", version 2, length), a JSON chunk (padded with spaces to
// 4 bytes) and one BIN chunk (padded with zeros) holding, in order: POSITION (float VEC3,
// with the min/max the specification requires), NORMAL when given (float VEC3), each extra
// attribute (float SCALAR or VEC3), the triangle indices (uint32) and the edge indices
// (uint32). Every buffer view starts on a 4-byte boundary. Node 0 holds the triangle mesh
// (material 0: KHR_materials_unlit, white, double-sided: vertex colours are shown as they
// are), node 1 the edge mesh (material 1, unlit black; node extras {"role": "patch edges"}),
// the last node the camera (glTF cameras look along their local -Z with +Y up).
//
// glTF limits what it names: attribute names are COLOR_n (VEC3 colours), NORMAL, or
// application-specific ones starting with '_' (e.g. _TEMPERATURE). Values must be finite.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "io/json.hpp"

namespace lambert {

/// A per-vertex attribute: its glTF name and 1 (SCALAR) or 3 (VEC3) floats per vertex.
struct GlbAttribute {
  std::string name;
  int components = 3;
  std::vector<float> values;  ///< components per vertex, vertex-major
};

/// A perspective camera: the eye looking at `look_at` with `up`, a vertical field of view.
struct GlbCamera {
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  Eigen::Vector3d look_at = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  double yfov_degrees = 40.0;
  double aspect = 1.0;  ///< width / height
  double znear = 1e-3;  ///< in scene units
};

/// What one .glb holds.
struct GlbContent {
  std::vector<float> positions;          ///< 3 per vertex
  std::vector<float> normals;            ///< 3 per vertex, unit length; empty = none
  std::vector<std::uint32_t> triangles;  ///< 3 per triangle, counter-clockwise = front
  std::vector<std::uint32_t> edges;      ///< 2 per line segment; empty = no edge mesh
  std::vector<GlbAttribute> attributes;  ///< extra per-vertex attributes, in order
  std::optional<GlbCamera> camera;
  std::string generator = "lambert";  ///< asset.generator
  Json asset_extras = Json();         ///< asset.extras (null = none)
  Json primitive_extras = Json();     ///< the triangle primitive's extras (null = none)
};

/// The bytes of the .glb. Inconsistent content (sizes, an index out of range, a non-finite
/// value, an attribute name glTF does not allow, >= 2^31 vertices) is a bug of the caller:
/// InternalError (LAMBERT_CHECK).
std::string glb_bytes(const GlbContent& content);

/// Writes glb_bytes(content) to `path` atomically. Throws IoError.
void write_glb(const std::string& path, const GlbContent& content);

}  // namespace lambert
