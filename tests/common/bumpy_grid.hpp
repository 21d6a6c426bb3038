#pragma once
// A generated stand-in for a scanned model (the meshing plan's tests and bench/meshing_bench):
// one connected surface of 2 m² triangles over the unit square, a jittered height field
// (corners moved by up to 15 % of a cell, heights up to 5 % of the side), each cell split
// along a random diagonal; so the edge lengths vary like a scan's and every triangle shares
// its edges with its neighbours. Deterministic in (m, seed).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "core/sampling.hpp"
#include "geometry/scene.hpp"

namespace lambert::test {

/// The bumpy grid of m x m cells (2 m² triangles, (m + 1)² vertices) as surface "grid".
inline Scene bumpy_grid(int m, std::uint64_t seed = 1) {
  Scene s;
  s.materials.push_back({"white", Eigen::Vector3d::Constant(0.5)});
  s.surfaces.push_back({"grid", 0});
  Rng rng(seed);
  const double d = 1.0 / m;
  for (int i = 0; i <= m; ++i)
    for (int j = 0; j <= m; ++j) {
      const double x = i * d + 0.3 * d * (rng.uniform() - 0.5);
      const double z = j * d + 0.3 * d * (rng.uniform() - 0.5);
      const double y = 0.04 * std::sin(7.0 * x) * std::cos(5.0 * z) + 0.01 * rng.uniform();
      s.vertices.emplace_back(x, y, z);
    }
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(i * (m + 1) + j); };
  auto add = [&](std::int32_t a, std::int32_t b, std::int32_t c) {
    Face f;
    f.vertices = {a, b, c};
    s.faces.push_back(std::move(f));
  };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const auto a = id(i, j), b = id(i, j + 1), c = id(i + 1, j + 1), e = id(i + 1, j);
      if (rng.uniform() < 0.5) {
        add(a, b, c);
        add(a, c, e);
      } else {
        add(a, b, e);
        add(b, c, e);
      }
    }
  return s;
}

}  // namespace lambert::test
