#pragma once
// What every accepted scene of a loader fuzz target must hold: faces, each on a valid surface
// with valid corners. A violation aborts (libFuzzer reports it as a crash).
#include <cstddef>
#include <cstdlib>

#include "geometry/scene.hpp"

inline void check_fuzzed_scene(const lambert::Scene& s) {
  if (s.faces.empty()) std::abort();
  for (const auto& f : s.faces) {
    if (f.surface < 0 || static_cast<std::size_t>(f.surface) >= s.surfaces.size()) std::abort();
    for (const auto v : f.vertices)
      if (v < 0 || static_cast<std::size_t>(v) >= s.vertices.size()) std::abort();
  }
}
