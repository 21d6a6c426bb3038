// The hierarchical method against the matrix method on the built-in Cornell box.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/hierarchical/hierarchical.hpp"
#include "io/obj_loader.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {
namespace {

// Per-surface area-weighted average radiosity.
std::vector<Eigen::Vector3d> surface_means(const PatchMesh& mesh, const Eigen::MatrixX3d& B) {
  std::vector<Eigen::Vector3d> sum(mesh.surface_names.size(), Eigen::Vector3d::Zero());
  std::vector<double> area(mesh.surface_names.size(), 0.0);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    sum[mesh.patches[i].surface] += mesh.patches[i].area * B.row(i).transpose();
    area[mesh.patches[i].surface] += mesh.patches[i].area;
  }
  for (std::size_t s = 0; s < sum.size(); ++s)
    if (area[s] > 0) sum[s] /= area[s];
  return sum;
}

std::vector<Eigen::Vector3d> matrix_means(const Scene& scene, std::int64_t patches) {
  MeshOptions mo;
  mo.target_patches = patches;
  const PatchMesh mesh = mesh_scene(scene, mo);
  FormFactorOptions fo;
  fo.estimator = "hybrid";
  fo.samples = 4;
  const FormFactors F = compute_form_factors(mesh, fo);
  RadiosityProblem p;
  p.F = std::make_shared<CsrOperator>(F.F);
  p.rho.resize(mesh.size(), 3);
  p.emission.resize(mesh.size(), 3);
  p.area.resize(mesh.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    p.rho.row(i) = mesh.patches[i].rho.transpose();
    p.emission.row(i) = mesh.patches[i].emission.transpose();
    p.area[i] = mesh.patches[i].area;
  }
  SolveOptions so;
  so.tol = 1e-10;
  const RadiositySolution sol = solve_radiosity(p, so);
  return surface_means(mesh, sol.B);
}

TEST(HierarchicalCornell, DISABLED_MatrixTrend) {
  const Scene scene = load_obj(builtin_cornell_box_path());
  for (long n : {500L, 2000L, 8000L}) {
    const auto m = matrix_means(scene, n);
    std::printf("matrix %ld:", n);
    for (auto& v : m) std::printf(" %.6g", v[0]);
    std::printf("\n");
  }
}

TEST(HierarchicalCornell, Explore) {
  Scene scene = load_obj(builtin_cornell_box_path());
  if (std::getenv("NO_BLOCKS")) {
    std::vector<Face> keep;
    for (auto& f : scene.faces) if (scene.surfaces[f.surface].name.find("block") == std::string::npos) keep.push_back(f);
    scene.faces = keep;
  }
  if (const char* recv = std::getenv("PAIR")) {  // PAIR=emitter,receiver
    const std::string spec = recv;
    const std::string em = spec.substr(0, spec.find(',')), rc = spec.substr(spec.find(',') + 1);
    for (auto& f : scene.faces) f.rho.reset();
    for (auto& s : scene.surfaces) {
      Material mat;
      mat.name = s.name;
      if (s.name == em) mat.emission.setConstant(em == "light" ? 17.0 : 1.0);
      if (rc.find(s.name) != std::string::npos) mat.rho.setConstant(0.5);
      scene.materials.push_back(mat);
      s.material = scene.materials.size() - 1;
    }
  }
  if (std::getenv("DIRECT_ONLY")) {
    for (auto& f : scene.faces) f.rho.reset();
    for (std::size_t m = 0; m < scene.materials.size(); ++m) scene.materials[m].rho.setZero();
    for (auto& s : scene.surfaces) if (s.name == "floor") { Material mat = scene.materials[s.material]; mat.rho = Eigen::Vector3d(0.5,0.5,0.5); mat.name="x"; scene.materials.push_back(mat); s.material = scene.materials.size()-1; }
  }
  const auto ref = matrix_means(scene, 2000);
  for (double eps : {std::getenv("EPS") ? std::atof(std::getenv("EPS")) : 1e-3, 1e-4, 1e-5}) {
    HierarchicalOptions o;
    o.epsilon = eps;
    const HierarchicalResult r = solve_hierarchical(scene, o);
    const auto m = surface_means(r.mesh, r.B);
    double worst = 0;
    for (std::size_t s = 0; s < m.size(); ++s)
      for (int c = 0; c < 3; ++c)
        if (ref[s][c] > 0) {
          worst = std::max(worst, std::abs(m[s][c] / ref[s][c] - 1));
          if (c == 0) std::printf("  %-12s %.5g %.5g %+.4f\n", r.mesh.surface_names[s].c_str(), m[s][c], ref[s][c], m[s][c] / ref[s][c] - 1);
        }
    const auto& st = r.stats;
    std::printf("eps %g: leaves %lld links %lld (cl %lld) rays %lld passes %d it %d conv %d  t %.2f+%.2f+%.2f  worst %.4f imb %.2e esc %.3g/%.3g\n",
                eps, (long long)st.leaves, (long long)st.links, (long long)st.cluster_links,
                (long long)st.rays, st.passes, st.iterations, st.converged, st.build_seconds,
                st.refine_seconds, st.solve_seconds, worst, st.energy[0].relative_imbalance,
                st.energy[0].escaped, st.energy[0].emitted);
  }
}

}  // namespace
}  // namespace lambert
