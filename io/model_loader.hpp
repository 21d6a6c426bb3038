#pragma once
// Scenes in the formats of 3D tools (glTF/GLB, FBX, COLLADA, 3DS, Blender, ...) read through
// assimp (docs/scenes.md, "Other formats"). OBJ, STL and PLY keep lambert's own readers.

#include <string>

#include "geometry/scene.hpp"
#include "io/obj_loader.hpp"

namespace lambert {

/// True when lambert reads `path` through assimp: a GLB or binary FBX by its first bytes
/// `head`, any other file by an extension assimp takes that is not .obj, .stl or .ply.
bool looks_like_model(const std::string& path, const std::string& head);

/// Loads a scene through assimp. Every mesh instance of the node tree becomes one surface
/// named by its node (and mesh, when a node holds several), placed by the node transforms
/// (a mirroring transform keeps the front: the corner order is reversed). Polygons are kept
/// (non-planar ones split as in every loader); points and lines are skipped and counted.
/// Materials map to rho (glTF's base colour, else the diffuse colour; channels clamped to
/// [0, 1], counted in a warning) and E (the emissive colour times glTF's emissive strength);
/// a colour texture is not sampled (its factor is used; counted in a warning). Then
/// `--emit` rules apply; a camera sidecar `<stem>.camera` as for OBJ, otherwise the
/// three-quarter view, y up. The reader runs in a child process: a file that makes it
/// crash, loop (longer than 60 s + 4 s per MB) or fail is a SceneError naming the file and
/// why, never a crash of lambert.
Scene load_model(const std::string& path, LoadReport* report = nullptr,
                 const LoadOptions& options = {});

}  // namespace lambert
