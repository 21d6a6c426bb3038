#include "pipeline/relight.hpp"

#include <algorithm>
#include <utility>

#include "core/timer.hpp"

namespace lambert {
namespace {

double total(const Eigen::Vector3d& v) { return v.sum(); }

Eigen::Vector3d power_of(const PatchMesh& mesh, const Eigen::MatrixX3d& E) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (std::int32_t i = 0; i < mesh.size(); ++i) p += mesh.patches[i].area * E.row(i).transpose();
  return p;
}

// ρ_i H_i: a daylight source's first bounce off every patch.
Eigen::MatrixX3d reflected(const PatchMesh& mesh, const Eigen::MatrixX3d& H) {
  Eigen::MatrixX3d E(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    E.row(i) = mesh.patches[i].rho.cwiseProduct(H.row(i).transpose()).transpose();
  return E;
}

}  // namespace

std::vector<EmitterBasis> emitter_sources(const PatchMesh& mesh, const DaylightSources& daylight) {
  std::vector<EmitterBasis> surfaces;
  for (std::size_t s = 0; s < mesh.surface_names.size(); ++s) {
    EmitterBasis b;
    b.name = mesh.surface_names[s];
    b.kind = "surface";
    b.surfaces = {b.name};
    b.E = Eigen::MatrixX3d::Zero(mesh.size(), 3);
    surfaces.push_back(std::move(b));
  }
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    if (p.emission.maxCoeff() > 0.0) surfaces.at(p.surface).E.row(i) = p.emission.transpose();
  }
  std::vector<EmitterBasis> out;
  for (EmitterBasis& b : surfaces) {
    b.power = power_of(mesh, b.E);
    if (b.power.maxCoeff() > 0.0) out.push_back(std::move(b));
  }
  // Largest first; a stable sort keeps the scene's order among equals.
  std::stable_sort(out.begin(), out.end(), [](const EmitterBasis& a, const EmitterBasis& b) {
    return total(a.power) > total(b.power);
  });
  std::vector<EmitterBasis> light;
  const auto add_daylight = [&](const char* name, const Eigen::MatrixX3d& H) {
    if (H.rows() != mesh.size()) return;
    EmitterBasis b;
    b.name = b.kind = name;
    b.E = reflected(mesh, H);
    b.power = power_of(mesh, b.E);
    if (b.power.maxCoeff() > 0.0) light.push_back(std::move(b));
  };
  add_daylight("sky", daylight.sky);
  add_daylight("sun", daylight.sun);
  const std::size_t room = kMaxEmitterBases - light.size();
  if (out.size() > room) {  // the smallest surfaces share the last basis
    EmitterBasis rest;
    rest.name = "other emitters";
    rest.kind = "surfaces";
    rest.E = Eigen::MatrixX3d::Zero(mesh.size(), 3);
    for (std::size_t k = room - 1; k < out.size(); ++k) {
      rest.E += out[k].E;
      rest.surfaces.push_back(out[k].name);
    }
    rest.power = power_of(mesh, rest.E);
    out.resize(room - 1);
    out.push_back(std::move(rest));
  }
  for (EmitterBasis& b : light) out.push_back(std::move(b));
  return out;
}

double solve_emitter_bases(const RadiosityProblem& problem, const Eigen::MatrixX3d& B,
                           SolveOptions options, std::vector<EmitterBasis>& bases) {
  const Timer timer;
  if (bases.size() == 1) {
    bases[0].B = B;
    return 0.0;
  }
  options.tol = std::min(options.tol, kBasisTolerance);
  options.initial_guess.resize(0, 3);
  for (EmitterBasis& b : bases) {
    RadiosityProblem p = problem;
    p.emission.topRows(b.E.rows()) = b.E;
    b.B = solve_radiosity(p, options).B.topRows(b.E.rows());
  }
  return timer.seconds();
}

}  // namespace lambert
