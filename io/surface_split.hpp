#pragma once
// --split-angle: a loaded surface split into the pieces that feature edges bound (the base
// and each fin of a CAD heat sink become surfaces of their own).

#include <string>

#include "geometry/scene.hpp"

namespace lambert {

/// The computed angle may exceed an exact DEG by double rounding (atan2 and the degree
/// conversion: ~1e-14 degrees); an edge counts as "at most DEG" up to this slack, which is
/// far below any feature angle a model is drawn with.
inline constexpr double kSplitAngleSlackDeg = 1e-9;

/// Splits every surface of `scene` at its feature edges. Two faces of one surface that share
/// an edge (the same two corner positions) stay together when the angle between their front
/// normals is at most `max_angle_deg` (<=: exactly DEG keeps them together); an edge of more
/// than two faces (non-manifold) and faces that share only a corner separate. The pieces
/// (connected components of that relation) become surfaces with the surface's material: a
/// surface that stays whole keeps its name, one that splits becomes NAME/face_1,
/// NAME/face_2, ... numbered in order of each piece's first face in `scene.faces` (file
/// order). Surfaces are renumbered in that order. `name` names the file in messages: a
/// SceneError when a new name is already a surface's. O(E log E) for E face edges (one
/// sorted edge list, union-find); no per-pair loop.
void split_surfaces_at_feature_edges(Scene& scene, double max_angle_deg, const std::string& name);

}  // namespace lambert
