// View-pass benchmark (issue 14): time per image for Gouraud, raytrace and final gather
// with N gather rays, and the error of each against a refined solution, on the built-in
// Cornell box.
//
// The coarse solution (--patches, gather estimator with 1024 rays per patch, Gauss-Seidel
// to 1e-10) is rendered with Gouraud shading (conservative vertices), the view pass without
// a gather (the same image on this diffuse scene), and final gather with each N of --gather.
// The reference is a refined solve (--ref-patches, same estimator and solver) rendered with
// Gouraud shading over exact-direct vertices (exact direct light at every vertex plus the
// area-weighted indirect light, vertex_field.hpp): sharp shadows where the coarse field
// smears them. Errors are over the pixels every image covers (alpha 1): relative L1,
// Σ|L − L_ref| / Σ L_ref, and relative RMS, √(Σ (L − L_ref)²) / √(Σ L_ref²), over the three
// channels. One sample per pixel (pixel centres) for every image, so timings compare per
// camera ray.
//
// Usage: render_bench [--size 512] [--patches 800] [--ref-patches 8000]
//   [--gather 16,64,256] [--direct 8,32] [--threads 0] [--png-dir DIR]
//
// `--direct N` rows: Gouraud over the vertex field of E + rho I with the emitters' direct
// light drawn per pixel by N shadow rays (what `run` draws by default, N = 8).

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "core/timer.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/render/render.hpp"
#include "geometry/render/vertex_field.hpp"
#include "geometry/visibility/bvh.hpp"
#include "geometry/visibility/direct_light.hpp"
#include "io/obj_loader.hpp"
#include "io/tonemap.hpp"
#include "pipeline/problem.hpp"
#include "pipeline/render_stages.hpp"
#include "solvers/radiosity.hpp"

using namespace lambert;

namespace {

std::vector<int> parse_list(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stoi(item));
  return out;
}

struct Solved {
  PatchMesh mesh;
  Eigen::MatrixX3d B, indirect;
  double seconds = 0;
};

Solved solve(const Scene& scene, std::int64_t patches, int threads) {
  const Timer t;
  Solved s;
  MeshOptions mo;
  mo.target_patches = patches;
  s.mesh = mesh_scene(scene, mo);
  FormFactorOptions fo;
  fo.estimator = "gather";
  fo.gather.rays = 1024;
  fo.run.threads = threads;
  fo.run.progress = false;
  const FormFactors F = compute_form_factors(s.mesh, fo);
  SolveOptions so;
  so.tol = 1e-10;
  so.threads = threads;
  s.B = solve_radiosity(make_problem(s.mesh, F.F), so).B;
  s.indirect = indirect_irradiance(s.mesh, F.F, s.B);
  s.seconds = t.seconds();
  return s;
}

struct Errors {
  double l1 = 0, rms = 0;
};

Errors errors(const Image& img, const Image& ref) {
  double d1 = 0, r1 = 0, d2 = 0, r2 = 0;
  for (size_t k = 0; k < ref.alpha.size(); ++k) {
    if (img.alpha[k] < 1.0f || ref.alpha[k] < 1.0f) continue;
    for (int c = 0; c < 3; ++c) {
      const double a = img.rgb[3 * k + c], b = ref.rgb[3 * k + c];
      d1 += std::abs(a - b);
      r1 += std::abs(b);
      d2 += (a - b) * (a - b);
      r2 += b * b;
    }
  }
  return {d1 / r1, std::sqrt(d2 / r2)};
}

}  // namespace

int main(int argc, char** argv) {
  int size = 512, threads = 0;
  std::int64_t patches = 800, ref_patches = 8000;
  std::string gathers = "16,64,256", direct_rays = "8,32", png_dir;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--size")
      size = std::atoi(v.c_str());
    else if (a == "--patches")
      patches = std::atol(v.c_str());
    else if (a == "--ref-patches")
      ref_patches = std::atol(v.c_str());
    else if (a == "--gather")
      gathers = v;
    else if (a == "--direct")
      direct_rays = v;
    else if (a == "--threads")
      threads = std::atoi(v.c_str());
    else if (a == "--png-dir")
      png_dir = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  const Scene scene = load_obj(builtin_cornell_box_path());
  Camera cam = scene.camera;
  cam.width = cam.height = size;

  const Solved coarse = solve(scene, patches, threads);
  const Solved fine = solve(scene, ref_patches, threads);
  std::printf("Cornell box, %dx%d, 1 sample/pixel, --threads %d (0 = all cores)\n", size, size,
              threads);
  std::printf("coarse solve: %d patches in %.1f s; reference solve: %d patches in %.1f s\n",
              coarse.mesh.size(), coarse.seconds, fine.mesh.size(), fine.seconds);

  RenderSettings base;
  base.antialias = 1;
  base.threads = threads;
  base.progress = false;
  const auto write_png = [&](const std::string& name, const Image& img, double ev) {
    if (!png_dir.empty()) write_png_preview(png_dir + "/" + name + ".png", img, ev);
  };

  Timer t;
  const VertexField ref_field =
      exact_direct_vertex_field(scene, fine.mesh, fine.B, fine.indirect, threads);
  const Bvh ref_bvh(fine.mesh, threads);
  const Image ref = render(fine.mesh, ref_bvh, cam, fine.B, ref_field, base);
  const double ev = auto_exposure(ref);
  std::printf("reference image (exact-direct vertices, Gouraud): %.1f s\n\n", t.seconds());
  write_png("reference", ref, ev);

  const VertexField field = interpolate_to_vertices(coarse.mesh, coarse.B);
  const Bvh bvh(coarse.mesh, threads);
  const DirectLight light(scene);
  std::printf("%-22s %10s %12s %10s %10s %12s\n", "shading", "seconds", "rays", "vs gouraud",
              "L1 error", "RMS error");
  double gouraud_seconds = 0;
  const auto report = [&](const std::string& name, const RenderSettings& o,
                          const VertexField* shading_field = nullptr) {
    RenderStats stats;
    const Image img = render(coarse.mesh, bvh, cam, coarse.B,
                             shading_field ? *shading_field : field, o, &stats, &light);
    if (gouraud_seconds == 0) gouraud_seconds = stats.seconds;
    const Errors e = errors(img, ref);
    std::printf("%-22s %10.2f %12lld %9.1fx %10.4f %12.4f\n", name.c_str(), stats.seconds,
                static_cast<long long>(stats.rays), stats.seconds / gouraud_seconds, e.l1, e.rms);
    std::fflush(stdout);
    write_png(name, img, ev);
    return stats.seconds;
  };
  report("gouraud", base);
  // The emitters' direct light per pixel (pixel_direct.hpp) over the vertex field of E + rho I,
  // as `run` draws it by default.
  const VertexField rest_field =
      emitted_and_indirect_field(coarse.mesh, coarse.indirect, VertexInterpolation::Conservative);
  for (int n : parse_list(direct_rays)) {
    const PixelDirectLight pixel(scene, n, 1e-6 * coarse.mesh.scale);
    RenderSettings o = base;
    o.pixel_direct = &pixel;
    report("gouraud+direct-" + std::to_string(n), o, &rest_field);
  }
  RenderSettings traced = base;
  traced.shading = Shading::Raytrace;
  report("raytrace", traced);
  double previous = 0;
  for (int n : parse_list(gathers)) {
    RenderSettings o = traced;
    o.view.final_gather = n;
    const double s = report("final-gather-" + std::to_string(n), o);
    if (previous > 0) std::printf("%22s time ratio to the previous N: %.2f\n", "", s / previous);
    previous = s;
  }
  // The exact direct light alone, per point (what final gather pays once per camera hit).
  const int probes = 2000;
  std::vector<Eigen::Vector3d> points, normals;
  for (int k = 0; k < probes; ++k) {
    const Patch& p = coarse.mesh.patches[(k * 7919) % coarse.mesh.size()];
    points.push_back(p.centroid);
    normals.push_back(p.normal);
  }
  t = Timer();
  exact_direct_irradiance(scene, points, normals, 1);
  std::printf("\nexact direct light: %.1f us per point (one thread, %d patch centroids)\n",
              1e6 * t.seconds() / probes, probes);
  return 0;
}
