#pragma once
// A generated scene family for the hierarchical benchmark (issue 12): the built-in Cornell
// box (its light stays the only emitter) filled with many finely tessellated ellipsoids, at
// any input-triangle count from ~10^2 to ~10^7.
//
// Objects. M = max(1, round(sqrt(T) / 2)) ellipsoids (T the target; 16 at 10^3, 500 at
// 10^6), each a geodesic sphere (an octahedron whose 8 faces are split into k^2 triangles,
// vertices projected radially: 8 k^2 triangles, 4 k^2 + 2 vertices, no slivers) scaled to
// semi-axes (a, b, c) and turned about the vertical. k is chosen per object so that the
// triangles still to place are spread evenly over the objects still to place; the total is
// within ~8 (2k + 1) triangles of the target (under 3 % at 10^3, under 0.5 % from 10^4).
// The first ones rest on the floor (0.2 % of the box size above it; as many as cover ~35 %
// of the free floor, at most half), the others float. Their bounding spheres keep at least
// 1 % of the box size from each other, from the walls, floor and ceiling and from the
// blocks' bounding boxes; the objects fill about 8 % of the free volume. Each object is its
// own surface `object_NNNN`; materials cycle through the box's white and three added ones
// (blue, yellow, grey). Triangles are wound counter-clockwise about the outward normal
// (fronts outward), checked for every triangle.
//
// Deterministic: the same (target, seed) gives the same scene.

#include <cstdint>

#include "geometry/scene.hpp"

namespace lambert::bench {

/// Triangles of a scene's faces, a face of n corners counting n - 2.
std::int64_t triangle_count(const Scene& scene);

/// The Cornell box with tessellated ellipsoids, about `target_triangles` input triangles in
/// all (the box's own faces included). Throws UsageError for a target below the box's own
/// triangles + 8 or above 10^8.
Scene cornell_with_objects(std::int64_t target_triangles, std::uint64_t seed = 1);

}  // namespace lambert::bench
