#pragma once
// PLY (Stanford polygon file) scene loading: ASCII, binary little- and big-endian, read by
// lambert's own strict reader (docs/scenes.md, "PLY files").

#include <string>

#include "geometry/scene.hpp"
#include "io/obj_loader.hpp"

namespace lambert {

/// True when the bytes `head` (the start of a file) are a PLY header: the line "ply".
bool looks_like_ply(const std::string& head);

/// Loads a PLY file: the element `vertex` (properties x, y, z of any numeric type; others,
/// such as normals and colours, are read past) and the element `face` (a list property
/// `vertex_indices` or `vertex_index`, each face a polygon wound counter-clockwise about its
/// front); other elements (edges, materials, ...) are read past. One surface per connected
/// component (faces sharing a corner position), named after the file's stem (STEM_1,
/// STEM_2, ... when there are several). Zero-area faces are dropped and non-planar polygons
/// split into triangles, each counted in one warning. Every surface gets the default material
/// (no emission), then `--emit` rules apply; with --vertex-colors-as-reflectance a face whose
/// corners all carry red, green and blue reflects their mean (uchar/255, or floats in [0, 1]).
/// A camera sidecar `<stem>.camera` is read as for OBJ; otherwise a three-quarter view, y up.
/// Throws IoError (missing file) or SceneError naming the file and the header line, or the
/// element and its number, and what is wrong: an unknown format or type, a count the file
/// cannot hold, a truncated body, bytes after it, a non-finite coordinate, an index out of
/// range, a face with fewer than 3 corners, no face at all (a point cloud).
Scene load_ply(const std::string& path, LoadReport* report = nullptr,
               const LoadOptions& options = {});

/// load_ply from the file's bytes, named `name` in messages (no camera sidecar). For tests
/// and fuzzing.
Scene load_ply_bytes(const std::string& bytes, const std::string& name,
                     LoadReport* report = nullptr, const LoadOptions& options = {});

}  // namespace lambert
