#include "pipeline/problem.hpp"

#include <cmath>

#include "core/error.hpp"

namespace lambert {

Eigen::MatrixX3d indirect_irradiance(const PatchMesh& mesh, const SparseRowMatrix& F,
                                     const Eigen::MatrixX3d& B) {
  LAMBERT_CHECK(F.rows() == mesh.size() && F.cols() == mesh.size() && B.rows() == mesh.size(),
                "form factors and radiosity do not match the mesh");
  Eigen::MatrixX3d reflected = B;
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    reflected.row(i) -= mesh.patches[i].emission.transpose();
  return F * reflected;
}

RadiosityProblem make_extended_problem(const PatchMesh& mesh, const SparseRowMatrix& F,
                                       const Eigen::MatrixX3d& extra_rho,
                                       const Eigen::MatrixX3d& extra_emission,
                                       const Eigen::VectorXd& extra_area) {
  const std::int32_t n = mesh.size();
  const auto m = static_cast<std::int32_t>(extra_area.size());
  LAMBERT_CHECK(extra_rho.rows() == m && extra_emission.rows() == m,
                "extra unknowns' reflectance, emission and area differ in count");
  if (F.rows() != n + m || F.cols() != n + m)
    throw SceneError("form factors are " + std::to_string(F.rows()) + "x" +
                     std::to_string(F.cols()) + " but the mesh has " + std::to_string(n) +
                     " patches" + (m > 0 ? " and " + std::to_string(m) + " zones" : std::string()));
  RadiosityProblem p;
  p.F = std::make_shared<CsrOperator>(F);
  p.rho.resize(n + m, 3);
  p.emission.resize(n + m, 3);
  p.area.resize(n + m);
  for (std::int32_t i = 0; i < n; ++i) {
    const Patch& patch = mesh.patches[i];
    // rho = 1 (lossless) is passed as it is: check_closed_lossless has ruled out the one
    // singular case, a closed set of lossless patches.
    p.rho.row(i) = patch.rho.transpose();
    p.emission.row(i) = patch.emission.transpose();
    p.area[i] = patch.area;
  }
  p.rho.bottomRows(m) = extra_rho;
  p.emission.bottomRows(m) = extra_emission;
  p.area.tail(m) = extra_area;
  return p;
}

RadiosityProblem make_problem(const PatchMesh& mesh, const SparseRowMatrix& F) {
  return make_extended_problem(mesh, F, Eigen::MatrixX3d(0, 3), Eigen::MatrixX3d(0, 3),
                               Eigen::VectorXd(0));
}

RadiosityProblem make_problem(const PatchMesh& mesh, const FormFactors& ff) {
  RadiosityProblem p = make_problem(mesh, ff.F);
  if (ff.specular_continued.size() == mesh.size()) p.continued = ff.specular_continued;
  return p;
}

std::vector<SurfaceRadiosity> surface_averages(const PatchMesh& mesh, const Eigen::MatrixX3d& B) {
  std::vector<SurfaceRadiosity> out(mesh.surface_names.size());
  for (size_t s = 0; s < out.size(); ++s) out[s].name = mesh.surface_names[s];
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    SurfaceRadiosity& s = out.at(p.surface);
    s.area += p.area;
    ++s.patches;
    s.average += p.area * B.row(i).transpose();
  }
  for (auto& s : out)
    if (s.area > 0.0) s.average /= s.area;
  return out;
}

}  // namespace lambert
