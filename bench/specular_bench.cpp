// Extended form factors (geometry/formfactors/specular.hpp), measured in one run:
//  1. convergence: the plane-mirror case of the tests (two plates under a mirror, exact by
//     the image method) at K = 64 ... 16384 specular rays per patch: error, the stated
//     standard error, their ratio, time, and the log-log slope of the error against K;
//  2. cost on the specular Cornell box (data/cornell_box_specular): F without the specular
//     part (--specular-depth 0) against the extended F at the same settings, the specular
//     part's segments per second against raw Embree closest-hit rays on the same BVH, and
//     the mean segments per path.
// Usage: specular_bench [--rays 64,256,1024,4096,16384] [--patches N] [-j N]

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bench/power_law.hpp"
#include "bench/raw_rays.hpp"
#include "core/timer.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/formfactors/specular.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/obj_loader.hpp"

using namespace lambert;

namespace {

std::vector<int> parse_list(const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) out.push_back(std::atoi(item.c_str()));
  return out;
}

// The test scene: plates a = [0,1]² and b = [1.5,2.5] x [0,0.6] in z = 0 facing up, a mirror
// of ρ_s = 0.8 at z = 0.5 facing down.
Scene mirror_over_plates() {
  Scene s;
  const Material white("white", Eigen::Vector3d::Constant(0.5));
  Specular sp;
  sp.reflectance.setConstant(0.8);
  const Material mirror("mirror", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), sp);
  add_polygon(s, "a", white, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  add_polygon(s, "b", white, {{1.5, 0, 0}, {2.5, 0, 0}, {2.5, 0.6, 0}, {1.5, 0.6, 0}});
  add_polygon(s, "mirror", mirror, {{-2, -2, 0.5}, {-2, 2.6, 0.5}, {4.5, 2.6, 0.5}, {4.5, -2, 0.5}});
  return s;
}

FormFactorOptions options(int rays, int depth, int threads) {
  FormFactorOptions o;
  o.estimator = "gather";
  o.gather.rays = 1024;
  o.specular.rays = rays;
  o.specular.depth = depth;
  o.run.threads = threads;
  o.run.with_stderr = true;
  o.run.progress = false;
  return o;
}

void convergence(const std::vector<int>& rays, int threads) {
  const PatchMesh mesh = mesh_scene(mirror_over_plates(), {0.25, 0});
  const double exact = 0.8 * parallel_rectangles_G(0, 1, 0, 1, 1.5, 2.5, 0, 0.6, 1.0);
  std::printf("1. plane mirror, image method: F_ab = %.9f (a: 16 patches, b: 12)\n", exact);
  std::printf("%8s %12s %10s %10s %8s %9s\n", "K", "F_ab", "error", "stderr", "err/se",
              "seconds");
  std::vector<std::pair<double, double>> errors, stderrs;
  for (const int k : rays) {
    const Timer t;
    const FormFactors ff = compute_form_factors(mesh, options(k, 8, threads));
    const double seconds = t.seconds();
    double g = 0.0, var = 0.0;
    for (std::int32_t i = 0; i < mesh.size(); ++i) {
      if (mesh.patches[i].surface != 0) continue;
      for (SparseF::InnerIterator it(ff.F, i); it; ++it) {
        if (mesh.patches[it.col()].surface != 1) continue;
        g += mesh.patches[i].area * it.value();
        var += std::pow(mesh.patches[i].area * ff.stderr_F.coeff(i, it.col()), 2);
      }
    }
    const double err = std::abs(g - exact), se = std::sqrt(var);
    std::printf("%8d %12.9f %10.2e %10.2e %8.2f %9.3f\n", k, g, err, se, err / se, seconds);
    errors.push_back({k, err});
    stderrs.push_back({k, se});
  }
  std::printf("error ~ K^%.2f, stderr ~ K^%.2f (log-log least squares; 1/sqrt(K) is -0.5)\n\n",
              fit_power_law(errors).p, fit_power_law(stderrs).p);
}

void cornell_cost(std::int64_t patches, int threads) {
  const std::filesystem::path data =
      std::filesystem::path(builtin_cornell_box_path()).parent_path().parent_path();
  const Scene scene = load_obj((data / "cornell_box_specular" / "cornell_box_specular.obj").string());
  const PatchMesh mesh = mesh_scene(scene, {0.0, patches});
  const Bvh bvh(mesh, threads);
  std::printf("2. specular Cornell box: %d patches (%lld asked), gather 1024 rays, specular 1024\n",
              mesh.size(), static_cast<long long>(patches));
  Timer t0;
  FormFactorOptions direct = options(1024, 0, threads);
  direct.run.with_stderr = false;
  const FormFactors d = compute_form_factors(mesh, direct, &bvh);
  const double direct_s = t0.seconds();
  Timer t1;
  FormFactorOptions full = options(1024, 8, threads);
  full.run.with_stderr = false;
  const FormFactors f = compute_form_factors(mesh, full, &bvh);
  const double full_s = t1.seconds();
  // The specular pass alone, then raw Embree on as many cosine rays, back to back.
  Timer t2;
  const ff::SpecularTransport sp = ff::compute_specular_transport(mesh, full, bvh);
  const double specular_s = t2.seconds();
  const auto raw = hemisphere_rays(mesh, 1024);
  const double raw_rate = raw_closest_hit_rate(bvh, raw, threads);
  const double rate = static_cast<double>(sp.rays) / specular_s;
  std::printf("direct part (depth 0):   %8.3f s, %lld rays\n", direct_s,
              static_cast<long long>(d.stats.rays));
  std::printf("extended (depth 8):      %8.3f s, %lld rays (%lld on specular paths, %.2f "
              "segments per path)\n",
              full_s, static_cast<long long>(f.stats.rays),
              static_cast<long long>(f.stats.specular_rays),
              static_cast<double>(f.stats.specular_rays) / (1024.0 * mesh.size()));
  std::printf("extended / direct time:  %8.2fx; nnz %lld vs %lld\n", full_s / direct_s,
              static_cast<long long>(f.F.nonZeros()), static_cast<long long>(d.F.nonZeros()));
  std::printf("specular pass alone:     %8.3f s, %.3g segments/s vs raw Embree closest hit "
              "%.3g rays/s on the same BVH (ratio %.2f)\n",
              specular_s, rate, raw_rate, rate / raw_rate);
}

}  // namespace

int main(int argc, char** argv) {
  std::string rays = "64,256,1024,4096,16384";
  std::int64_t patches = 3000;
  int threads = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--rays")
      rays = v;
    else if (a == "--patches")
      patches = std::atol(v.c_str());
    else if (a == "-j")
      threads = std::atoi(v.c_str());
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  convergence(parse_list(rays), threads);
  cornell_cost(patches, threads);
  return 0;
}
