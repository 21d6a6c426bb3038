#pragma once
// ASCII STL text of generated triangles, for the tests that write scenes.

#include <Eigen/Core>
#include <array>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace lambert::testing {

/// A triangle's corners, counter-clockwise about its front.
using StlTriangle = std::array<Eigen::Vector3d, 3>;

/// One `solid NAME` block per entry, corners printed to 17 digits (read back as the same
/// doubles), zero stored normals (the loader orients facets by their vertex order).
inline std::string ascii_stl(
    const std::vector<std::pair<std::string, std::vector<StlTriangle>>>& solids) {
  std::string s;
  char buf[200];
  for (const auto& [name, tris] : solids) {
    s += "solid " + name + "\n";
    for (const auto& t : tris) {
      s += "facet normal 0 0 0\nouter loop\n";
      for (const auto& p : t) {
        std::snprintf(buf, sizeof buf, "vertex %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
        s += buf;
      }
      s += "endloop\nendfacet\n";
    }
    s += "endsolid " + name + "\n";
  }
  return s;
}

}  // namespace lambert::testing
