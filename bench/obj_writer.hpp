#pragma once
// A minimal Wavefront OBJ + MTL writer for generated scenes (benchmarks): what
// io/obj_loader reads back as the same scene (surfaces, materials, faces, camera).

#include <string>

#include "geometry/scene.hpp"

namespace lambert::bench {

/// Writes `scene` as `obj_path` (every vertex, then per surface `g NAME`, `usemtl MATERIAL`
/// and its faces), its materials as the MTL next to it (`Kd` = rho, `Ke` = E; the OBJ's
/// stem + ".mtl") and, when the scene has a camera, the sidecar `<stem>.camera`. Each file
/// is written atomically. Per-face reflectance (Face::rho) is not written: the generated
/// scenes have none. Numbers keep 17 significant digits, so positions round-trip exactly.
/// Throws IoError when a file cannot be written.
void write_obj(const Scene& scene, const std::string& obj_path);

}  // namespace lambert::bench
