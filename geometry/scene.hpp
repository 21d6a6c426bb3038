#pragma once
// The scene model: materials, named surfaces and their planar polygonal faces.
// Units are whatever the scene file uses (the Cornell box: millimetres); radiosity and
// emission are in W/m^2 of that unit system ("same units as E").

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "geometry/camera.hpp"

namespace lambert {

/// A Lambertian material: diffuse reflectance rho (RGB, each in [0,1)) and emitted
/// radiosity E (RGB, W/m^2, >= 0).
struct Material {
  std::string name;
  Eigen::Vector3d rho = Eigen::Vector3d::Zero();
  Eigen::Vector3d emission = Eigen::Vector3d::Zero();
  /// True when any channel of E is positive.
  bool emits() const { return emission.maxCoeff() > 0.0; }
};

/// A planar polygon, wound counter-clockwise about its front normal (right-hand rule).
struct Face {
  std::vector<std::int32_t> vertices;  ///< indices into Scene::vertices (>= 3)
  std::int32_t surface = 0;            ///< index into Scene::surfaces
  int line = 0;                        ///< source line of the face (0 if unknown)
  /// Reflectance of this face when it differs from its surface's material (vertex colours,
  /// --vertex-colors-as-reflectance); each channel in [0, 1]. Patches of the face get it.
  std::optional<Eigen::Vector3d> rho;
};

/// A named surface: one OBJ group/object with one material. Output is reported per surface.
struct Surface {
  std::string name;
  std::int32_t material = 0;  ///< index into Scene::materials
};

/// A whole scene as loaded from a file (or built by a test).
struct Scene {
  std::string source;  ///< file name it came from (for messages)
  /// Every file it was read from (the OBJ, its material libraries, its camera sidecar):
  /// the inputs that no output of a run may overwrite.
  std::vector<std::string> files;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Face> faces;
  std::vector<Surface> surfaces;
  std::vector<Material> materials;
  Camera camera;  ///< default view for rendering

  /// Sum of all face areas.
  double total_area() const;
  /// Axis-aligned bounding box (min, max) of the vertices used by faces.
  std::pair<Eigen::Vector3d, Eigen::Vector3d> bounds() const;
  /// Material of a surface.
  const Material& material_of(std::int32_t surface) const {
    return materials[surfaces[surface].material];
  }
};

/// Adds a planar polygon face on a (new or existing) surface; for tests and built-in scenes.
void add_polygon(Scene& scene, const std::string& surface, const Material& material,
                 const std::vector<Eigen::Vector3d>& corners);

}  // namespace lambert
