#pragma once
// The heat problem of `lambert heat` on a meshed scene, shared by the command (apps/heat.cpp)
// and the Python module: per-surface conditions (io/heat_surfaces.hpp) spread over the
// patches, scene units to metres, and the refusal of an enclosure that fixes no temperature.

#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/mesh/mesh.hpp"
#include "io/heat_surfaces.hpp"
#include "solvers/thermal.hpp"

namespace lambert {

/// The --length-unit names ("m", "cm", "mm", "in") and their metres per unit.
const std::vector<std::pair<std::string, double>>& length_units();

/// Metres per scene unit of `unit`; UsageError naming the accepted ones otherwise.
double metres_per_unit(const std::string& unit);

/// The exchange problem on `mesh`: per patch its surface's ε and known T or q, areas in m²
/// (`metres` per scene unit), F as the transport operator (F must outlive the problem), the
/// environment at `ambient` K.
ThermalProblem make_heat_problem(const PatchMesh& mesh, const std::vector<SurfaceCondition>& cond,
                                 const SparseRowMatrix& F, double metres, double ambient);

/// Throws SceneError naming `surfaces_file` and the surfaces when known-flux (or ε = 0)
/// surfaces enclose a space nothing escapes (find_closed_lossless on the thermal ρ): no
/// temperature fixes the level, the system is singular.
void refuse_floating_enclosure(const PatchMesh& mesh, const ThermalProblem& p,
                               const FormFactors& ff, const std::string& surfaces_file);

}  // namespace lambert
