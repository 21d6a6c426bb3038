#include "apps/problem.hpp"

#include <cmath>

#include "core/error.hpp"

namespace lambert {

Eigen::MatrixX3d indirect_irradiance(const PatchMesh& mesh, const SparseRowMatrix& F,
                                     const Eigen::MatrixX3d& B) {
  LAMBERT_CHECK(F.rows() == mesh.size() && F.cols() == mesh.size() && B.rows() == mesh.size(),
                "form factors and radiosity do not match the mesh");
  Eigen::MatrixX3d reflected = B;
  for (std::int32_t i = 0; i < mesh.size(); ++i) reflected.row(i) -= mesh.patches[i].emission.transpose();
  return F * reflected;
}

RadiosityProblem make_problem(const PatchMesh& mesh, const SparseRowMatrix& F) {
  const std::int32_t n = mesh.size();
  if (F.rows() != n || F.cols() != n)
    throw SceneError("form factors are " + std::to_string(F.rows()) + "x" +
                     std::to_string(F.cols()) + " but the mesh has " + std::to_string(n) +
                     " patches");
  RadiosityProblem p;
  p.F = std::make_shared<CsrOperator>(F);
  p.rho.resize(n, 3);
  p.emission.resize(n, 3);
  p.area.resize(n);
  for (std::int32_t i = 0; i < n; ++i) {
    const Patch& patch = mesh.patches[i];
    // rho = 1 (lossless) is passed as it is: check_closed_lossless has ruled out the one
    // singular case, a closed set of lossless patches.
    p.rho.row(i) = patch.rho.transpose();
    p.emission.row(i) = patch.emission.transpose();
    p.area[i] = patch.area;
  }
  return p;
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
