#include "geometry/scene.hpp"

#include <limits>

#include "geometry/polygon.hpp"

namespace lambert {

double Scene::total_area() const {
  double a = 0.0;
  std::vector<Eigen::Vector3d> poly;
  for (const auto& f : faces) {
    poly.clear();
    for (auto v : f.vertices) poly.push_back(vertices[v]);
    a += polygon_area(poly);
  }
  return a;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> Scene::bounds() const {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& f : faces) {
    for (auto v : f.vertices) {
      lo = lo.cwiseMin(vertices[v]);
      hi = hi.cwiseMax(vertices[v]);
    }
  }
  return {lo, hi};
}

void add_polygon(Scene& scene, const std::string& surface, const Material& material,
                 const std::vector<Eigen::Vector3d>& corners) {
  std::int32_t mat = -1;
  for (size_t m = 0; m < scene.materials.size(); ++m)
    if (scene.materials[m].name == material.name) mat = static_cast<std::int32_t>(m);
  if (mat < 0) {
    mat = static_cast<std::int32_t>(scene.materials.size());
    scene.materials.push_back(material);
  }
  std::int32_t surf = -1;
  for (size_t s = 0; s < scene.surfaces.size(); ++s)
    if (scene.surfaces[s].name == surface) surf = static_cast<std::int32_t>(s);
  if (surf < 0) {
    surf = static_cast<std::int32_t>(scene.surfaces.size());
    scene.surfaces.push_back({surface, mat});
  }
  Face f;
  f.surface = surf;
  for (const auto& c : corners) {
    f.vertices.push_back(static_cast<std::int32_t>(scene.vertices.size()));
    scene.vertices.push_back(c);
  }
  scene.faces.push_back(std::move(f));
}

}  // namespace lambert
