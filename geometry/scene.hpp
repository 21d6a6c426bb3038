#pragma once
// The scene model: materials, named surfaces and their planar polygonal faces.
// Units are whatever the scene file uses (the Cornell box: millimetres); radiosity and
// emission are in W/m^2 of that unit system ("same units as E").

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geometry/render/camera.hpp"

namespace lambert {

/// The perfect-specular part of a material (MTL `illum` 3, 5, 8: a mirror of reflectance Ks;
/// 4, 6, 7, 9: a dielectric interface of index Ni that reflects by Fresnel and refracts, the
/// refracted light filtered by Tf). Glossy lobes (Ns) are treated as perfect specular.
/// Light arriving at a surface splits into rho (diffuse), the specular part and the rest,
/// absorbed: a mirror needs rho + reflectance <= 1 per channel, a dielectric rho = 0.
struct Specular {
  Eigen::Vector3d reflectance = Eigen::Vector3d::Zero();  ///< mirror ρ_s per channel (Ks)
  bool dielectric = false;  ///< a refracting Fresnel interface (then `reflectance` is unused)
  double ior = 1.0;         ///< index of refraction behind the front side (Ni, dielectrics)
  Eigen::Vector3d transmission = Eigen::Vector3d::Ones();  ///< Tf: filter of refracted light
  double shininess = 0.0;   ///< Ns (reported only: every lobe is treated as a perfect one)
  /// True when rays that reach the surface continue (mirror with ρ_s > 0, or dielectric).
  bool any() const { return dielectric || reflectance.maxCoeff() > 0.0; }
  /// The largest fraction of arriving light the specular part can carry on, per channel
  /// (a dielectric's Fresnel reflectance reaches 1 at grazing incidence).
  Eigen::Vector3d max_fraction() const {
    return dielectric ? Eigen::Vector3d::Ones() : reflectance;
  }
};

/// A material: diffuse reflectance rho (RGB, each in [0,1]), emitted radiosity E (RGB,
/// W/m^2, >= 0) and an optional perfect-specular part.
struct Material {
  std::string name;
  Eigen::Vector3d rho = Eigen::Vector3d::Zero();
  Eigen::Vector3d emission = Eigen::Vector3d::Zero();
  Specular specular;

  Material() = default;
  /// A material from its parts (`{name, rho, emission}` as before the specular part).
  Material(std::string name_, const Eigen::Vector3d& rho_,
           const Eigen::Vector3d& emission_ = Eigen::Vector3d::Zero(), Specular specular_ = {})
      : name(std::move(name_)), rho(rho_), emission(emission_), specular(std::move(specular_)) {}
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

/// Light from outside the scene (docs/scenes.md, "Daylight"): a uniform sky and a sun.
/// The sky is a Lambertian dome of radiance `sky` (W m^-2 sr^-1 per channel, in the units
/// of the scene's emission per steradian) on every direction that escapes the scene; the
/// sun a directional source: `sun_irradiance` (W/m^2) on a surface facing it, its light
/// travelling along `sun_direction` (a unit vector; straight down in a y-up scene: 0,-1,0).
struct Daylight {
  Eigen::Vector3d sky = Eigen::Vector3d::Zero();
  Eigen::Vector3d sun_direction = Eigen::Vector3d::Zero();
  Eigen::Vector3d sun_irradiance = Eigen::Vector3d::Zero();
  bool has_sky() const { return sky.maxCoeff() > 0.0; }
  bool has_sun() const { return sun_irradiance.maxCoeff() > 0.0; }
  bool any() const { return has_sky() || has_sun(); }
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
  Daylight daylight;  ///< sky and sun (--sky, --sun); none by default

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
