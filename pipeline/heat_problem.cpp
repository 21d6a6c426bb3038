#include "pipeline/heat_problem.hpp"

#include <cmath>

#include "core/error.hpp"
#include "geometry/formfactors/analysis.hpp"

namespace lambert {

const std::vector<std::pair<std::string, double>>& length_units() {
  static const std::vector<std::pair<std::string, double>> kUnits = {
      {"cm", 0.01}, {"in", 0.0254}, {"m", 1.0}, {"mm", 0.001}};
  return kUnits;
}

double metres_per_unit(const std::string& unit) {
  std::string names;
  for (const auto& [name, metres] : length_units()) {
    if (name == unit) return metres;
    names += (names.empty() ? "" : ", ") + name;
  }
  throw UsageError("unknown length unit \"" + unit + "\" (one of " + names + ")");
}

ThermalProblem make_heat_problem(const PatchMesh& mesh, const std::vector<SurfaceCondition>& cond,
                                 const SparseRowMatrix& F, double metres, double ambient) {
  ThermalProblem p;
  const std::int32_t n = mesh.size();
  p.F = std::make_shared<CsrOperator>(F);
  p.area.resize(n);
  p.emissivity.resize(n);
  p.value.resize(n);
  p.boundary.resize(n);
  for (std::int32_t i = 0; i < n; ++i) {
    const SurfaceCondition& c = cond.at(mesh.patches[i].surface);
    p.area[i] = mesh.patches[i].area * metres * metres;
    p.emissivity[i] = c.emissivity;
    p.value[i] = c.value;
    p.boundary[i] = c.known_temperature ? ThermalBoundary::Temperature : ThermalBoundary::HeatFlux;
  }
  p.ambient_temperature = ambient;
  return p;
}

// An enclosure of known-flux (or ε = 0) surfaces from which nothing escapes fixes no
// temperature level: the system is singular. find_closed_lossless finds such closed sets of
// ρ = 1 patches within F's error; the patches' ρ is set to the thermal one for it.
void refuse_floating_enclosure(const PatchMesh& original, const ThermalProblem& p,
                               const FormFactors& ff, const std::string& surfaces_file) {
  PatchMesh mesh = original;
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const double rho = p.boundary[i] == ThermalBoundary::Temperature ? 1.0 - p.emissivity[i] : 1.0;
    mesh.patches[i].rho = Eigen::Vector3d::Constant(rho);
    mesh.patches[i].emission.setZero();
  }
  const auto closed = find_closed_lossless(mesh, ff);
  if (closed.empty()) return;
  std::string names;
  for (const auto s : closed.front().surfaces)
    names += (names.empty() ? "'" : ", '") + mesh.surface_names[s] + "'";
  throw SceneError(surfaces_file + ": surface(s) " + names +
                   " enclose a space with known heat flux (or emissivity 0) only and nothing "
                   "escapes it: no temperature fixes the level (the system is singular); give one "
                   "of them a temperature, or open the scene with --ambient-temperature");
}

}  // namespace lambert
