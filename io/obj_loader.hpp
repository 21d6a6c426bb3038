#pragma once
// Wavefront OBJ + MTL scene loading (tinyobjloader), with validation.

#include <string>

#include "geometry/scene.hpp"

namespace lambert {

/// What the loader had to repair (each also logged as a warning).
struct LoadReport {
  int degenerate_faces_dropped = 0;
  int nonplanar_faces_split = 0;
  bool has_emitter = false;
};

/// Loads an OBJ scene. `Kd` is the reflectance rho, `Ke` the emitted radiosity E. Each
/// OBJ group/object (and material within it) becomes a named surface. A sidecar file
/// `<name>.camera` next to the OBJ, if present, gives the default camera.
/// Throws IoError (missing/unreadable file) or SceneError (invalid content), with a
/// one-line message naming the file and line. Drops zero-area faces and splits non-planar
/// polygons into triangles, with warnings.
Scene load_obj(const std::string& path, LoadReport* report = nullptr);

/// Path of the built-in Cornell box scene.
std::string builtin_cornell_box_path();

}  // namespace lambert
