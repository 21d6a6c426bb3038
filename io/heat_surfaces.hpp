#pragma once
// The surfaces file of `lambert heat` (--surfaces FILE.json): per surface name a gray-diffuse
// emissivity and either a temperature (K) or a net heat flux (W/m²), with a "*" default.

#include <map>
#include <string>
#include <vector>

namespace lambert {

/// One surface's boundary condition as written in the file.
struct SurfaceCondition {
  double emissivity = 1.0;        ///< in [0, 1]
  bool known_temperature = true;  ///< true: `value` is T (K); false: q (W/m²)
  double value = 0.0;
};

/// The conditions of a surfaces file, by surface name ("*" = every surface not listed).
struct SurfaceConditions {
  std::string file;  ///< for messages
  std::map<std::string, SurfaceCondition> by_name;
};

/// Parses `text` (the JSON of file `name`): an object mapping each surface name (or "*") to
/// {"emissivity": E, "temperature": T} or {"emissivity": E, "heat_flux": Q}; emissivity in
/// [0, 1] (> 0 with heat_flux: a perfect reflector has no temperature to report), T >= 0,
/// every number finite, no other key. Throws SceneError "file: what" (exit 1).
SurfaceConditions parse_surface_conditions(const std::string& text, const std::string& name);

/// Reads and parses the file (IoError when it cannot be read).
SurfaceConditions read_surface_conditions(const std::string& path);

/// The condition of each of `surface_names` (in order): its own entry, else "*". Throws
/// SceneError naming the file and the surface for a surface with neither, and for a name in
/// the file that is no surface of the scene (a typo would otherwise silently take "*").
std::vector<SurfaceCondition> resolve_surface_conditions(
    const SurfaceConditions& conditions, const std::vector<std::string>& surface_names);

}  // namespace lambert
