// Scale benchmark (issue 11): the matrix path at 10^4 to 10^5 patches. Prints, for the
// Cornell box and a generated room full of tessellated objects (patches see each other
// sparsely), at each size:
//  - form-factor time of the estimator "gather" (K rays per patch) and its rays/s against
//    raw Embree closest-hit rays (rtcIntersect1) on the same BVH, in the same run, on rays
//    of the same distribution (stratified points, cosine directions; pre-generated so only
//    the traversal is timed), with the same thread count;
//  - nnz of F and the peak RSS of the whole case (forked child: its peak is its own; it
//    includes the mesh, BVH, the solvers' vectors and the 4M raw rays, ~100 MB, traced
//    before F), against the bytes of the final CSR;
//  - time to a relative residual of 1e-8 for gauss-seidel, bicgstab and cg.
// Usage: scale_bench [--sizes 10000,30000,100000] [--rays K] [-j N] [--scenes cornell,room]
// The machine is shared: compare ratios, and rerun for medians.

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench/child.hpp"
#include "bench/raw_rays.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/obj_loader.hpp"
#include "pipeline/problem.hpp"
#include "solvers/radiosity.hpp"

using namespace lambert;

namespace {

Material material(const char* name, double rho, double e = 0.0) {
  Material m;
  m.name = name;
  m.rho = Eigen::Vector3d::Constant(rho);
  m.emission = Eigen::Vector3d::Constant(e);
  return m;
}

// A 10 x 10 x 3 room (walls facing in), four ceiling lights, and a 6 x 6 grid of objects
// on the floor (boxes, UV spheres of 16 x 8 facets, 16-sided cylinders; outward faces):
// ~3,000 input faces, most patches hidden from most others.
Scene generated_room() {
  Scene s;
  const double L = 10.0, H = 3.0;
  const Material wall = material("wall", 0.7), floor_m = material("floor", 0.5),
                 obj = material("object", 0.6), lamp = material("lamp", 0.8, 10.0);
  add_polygon(s, "floor", floor_m, {{0, 0, 0}, {L, 0, 0}, {L, L, 0}, {0, L, 0}});
  add_polygon(s, "ceiling", wall, {{0, 0, H}, {0, L, H}, {L, L, H}, {L, 0, H}});
  add_polygon(s, "wall_y0", wall, {{0, 0, 0}, {0, 0, H}, {L, 0, H}, {L, 0, 0}});
  add_polygon(s, "wall_y1", wall, {{0, L, 0}, {L, L, 0}, {L, L, H}, {0, L, H}});
  add_polygon(s, "wall_x0", wall, {{0, 0, 0}, {0, L, 0}, {0, L, H}, {0, 0, H}});
  add_polygon(s, "wall_x1", wall, {{L, 0, 0}, {L, 0, H}, {L, L, H}, {L, L, 0}});
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      const double x = 2.5 + 5.0 * a, y = 2.5 + 5.0 * b, z = H - 0.01, h = 0.4;
      add_polygon(s, "lamp", lamp,
                  {{x - h, y - h, z}, {x - h, y + h, z}, {x + h, y + h, z}, {x + h, y - h, z}});
    }
  }
  Rng rng(2026);
  const int kGrid = 6, kSides = 16, kRings = 8;
  for (int gx = 0; gx < kGrid; ++gx) {
    for (int gy = 0; gy < kGrid; ++gy) {
      const double cx = L * (gx + 1) / (kGrid + 1), cy = L * (gy + 1) / (kGrid + 1);
      const std::string name = "object_" + std::to_string(gx) + "_" + std::to_string(gy);
      const int kind = (gx + 2 * gy) % 3;
      if (kind == 0) {  // box
        const double w = 0.3 + 0.4 * rng.uniform(), h = 0.4 + 1.6 * rng.uniform();
        const Eigen::Vector3d p0(cx - w, cy - w, 0), p1(cx + w, cy + w, h);
        add_polygon(s, name, obj, {{p0.x(), p0.y(), p1.z()}, {p1.x(), p0.y(), p1.z()},
                                   {p1.x(), p1.y(), p1.z()}, {p0.x(), p1.y(), p1.z()}});
        add_polygon(s, name, obj, {{p0.x(), p0.y(), 0}, {p1.x(), p0.y(), 0}, {p1.x(), p0.y(), h},
                                   {p0.x(), p0.y(), h}});
        add_polygon(s, name, obj, {{p1.x(), p1.y(), 0}, {p0.x(), p1.y(), 0}, {p0.x(), p1.y(), h},
                                   {p1.x(), p1.y(), h}});
        add_polygon(s, name, obj, {{p0.x(), p1.y(), 0}, {p0.x(), p0.y(), 0}, {p0.x(), p0.y(), h},
                                   {p0.x(), p1.y(), h}});
        add_polygon(s, name, obj, {{p1.x(), p0.y(), 0}, {p1.x(), p1.y(), 0}, {p1.x(), p1.y(), h},
                                   {p1.x(), p0.y(), h}});
      } else if (kind == 1) {  // UV sphere resting on the floor
        const double r = 0.3 + 0.3 * rng.uniform();
        auto at = [&](int ring, int side) {
          const double t = M_PI * ring / kRings, p = 2 * M_PI * side / kSides;
          return Eigen::Vector3d(cx + r * std::sin(t) * std::cos(p),
                                 cy + r * std::sin(t) * std::sin(p), r + r * std::cos(t));
        };
        for (int ring = 0; ring < kRings; ++ring) {
          for (int side = 0; side < kSides; ++side) {
            std::vector<Eigen::Vector3d> q = {at(ring, side), at(ring + 1, side),
                                              at(ring + 1, side + 1), at(ring, side + 1)};
            if (ring == 0) q.erase(q.begin() + 3);               // top cap: triangle
            if (ring == kRings - 1) q.erase(q.begin() + 1);      // bottom cap: triangle
            add_polygon(s, name, obj, q);
          }
        }
      } else {  // cylinder with a top cap
        const double r = 0.2 + 0.3 * rng.uniform(), h = 0.5 + 1.5 * rng.uniform();
        std::vector<Eigen::Vector3d> top;
        for (int side = 0; side < kSides; ++side) {
          const double p0 = 2 * M_PI * side / kSides, p1 = 2 * M_PI * (side + 1) / kSides;
          const Eigen::Vector3d a(cx + r * std::cos(p0), cy + r * std::sin(p0), 0);
          const Eigen::Vector3d b(cx + r * std::cos(p1), cy + r * std::sin(p1), 0);
          add_polygon(s, name, obj, {a, b, b + Eigen::Vector3d(0, 0, h), a + Eigen::Vector3d(0, 0, h)});
          top.push_back(a + Eigen::Vector3d(0, 0, h));
        }
        add_polygon(s, name, obj, top);
      }
    }
  }
  return s;
}

struct CaseResult {
  int patches = 0;
  double bvh_s = 0, raw_rate = 0, ff_s = 0, ff_rate = 0, rays = 0, average_s = 0, nnz = 0;
  double solve_s[3] = {0, 0, 0};
  int iterations[3] = {0, 0, 0};
  int converged[3] = {0, 0, 0};
  long max_rss_kb = 0;
};

const char* const kSolvers[3] = {"gauss-seidel", "bicgstab", "cg"};

CaseResult run_case(const std::string& scene_name, std::int64_t target, int rays_per_patch,
                    int threads) {
  CaseResult r;
  const Scene scene =
      scene_name == "cornell" ? load_obj(builtin_cornell_box_path()) : generated_room();
  const PatchMesh mesh = mesh_scene(scene, {0.0, target});
  r.patches = mesh.size();
  Timer tb;
  const Bvh bvh(mesh, threads);
  r.bvh_s = tb.seconds();
  // About 4M raw rays: enough for a stable rate, a few seconds at most.
  const int stride = std::max<std::int64_t>(1, static_cast<std::int64_t>(mesh.size()) * 64 / 4000000);
  r.raw_rate = raw_closest_hit_rate(bvh, hemisphere_rays(mesh, 64, stride), threads);  // freed here
  FormFactorOptions o;
  o.estimator = "gather";
  o.gather.rays = rays_per_patch;
  o.run.threads = threads;
  o.run.progress = false;
  const FormFactors ff = compute_form_factors(mesh, o, &bvh);  // averaged (the default)
  r.average_s = ff.stats.reciprocity_seconds;
  r.ff_s = ff.stats.seconds - r.average_s;
  r.rays = static_cast<double>(ff.stats.rays);
  r.ff_rate = r.rays / r.ff_s;
  r.nnz = static_cast<double>(ff.F.nonZeros());
  const RadiosityProblem problem = make_problem(mesh, ff.F);
  for (int s = 0; s < 3; ++s) {
    SolveOptions so;
    so.solver = kSolvers[s];
    so.tol = 1e-8;
    so.threads = threads;
    const RadiositySolution sol = solve_radiosity(problem, so);
    r.solve_s[s] = sol.seconds;
    for (const auto& c : sol.channels) r.iterations[s] += c.iterations;
    r.converged[s] = sol.status == SolveStatus::Converged;
  }
  return r;
}

CaseResult in_child(const std::string& scene, std::int64_t target, int rays, int threads) {
  long rss = 0;
  CaseResult r = run_in_child<CaseResult>([&] { return run_case(scene, target, rays, threads); }, rss);
  r.max_rss_kb = rss;
  return r;
}

std::vector<std::string> split(char* text) {
  std::vector<std::string> out;
  for (char* tok = std::strtok(text, ","); tok; tok = std::strtok(nullptr, ",")) out.push_back(tok);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  set_log_level(LogLevel::Quiet);
  int threads = resolve_threads(0);
  int rays = 1024;
  std::vector<std::int64_t> sizes = {10000, 30000, 100000};
  std::vector<std::string> scenes = {"cornell", "room"};
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "-j") && a + 1 < argc) threads = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--rays") && a + 1 < argc) rays = std::atoi(argv[++a]);
    else if (!std::strcmp(argv[a], "--scenes") && a + 1 < argc) scenes = split(argv[++a]);
    else if (!std::strcmp(argv[a], "--sizes") && a + 1 < argc) {
      sizes.clear();
      for (const std::string& s : split(argv[++a])) sizes.push_back(std::atoll(s.c_str()));
    } else {
      std::fprintf(stderr, "usage: scale_bench [--sizes N,N,...] [--rays K] [-j N] [--scenes cornell,room]\n");
      return 2;
    }
  }
  std::printf("estimator gather, %d rays per patch, %d threads\n\n", rays, threads);
  std::printf("ff: gather's tracing and assembly; avg: its reciprocity averaging (the default);\n"
              "nnz after averaging\n\n");
  std::printf("%-8s %8s %7s %9s %9s %6s %8s %7s %9s %8s %9s %7s | %-22s %-22s %-22s\n", "scene",
              "patches", "bvh s", "raw Mr/s", "ff Mr/s", "ratio", "ff s", "avg s", "nnz",
              "CSR MB", "peak MB", "peak/CSR", "gauss-seidel s (it)", "bicgstab s (it)",
              "cg s (it)");
  for (const std::string& scene : scenes) {
    for (const std::int64_t n : sizes) {
      const CaseResult r = in_child(scene, n, rays, threads);
      if (r.patches == 0) {
        std::printf("%-8s %8lld failed\n", scene.c_str(), static_cast<long long>(n));
        continue;
      }
      // The final CSR: 8-byte values and 8-byte column indices, 8-byte row starts.
      const double csr_mb = (16.0 * r.nnz + 8.0 * (r.patches + 1)) / 1048576.0;
      std::printf("%-8s %8d %7.2f %9.2f %9.2f %6.2f %8.1f %7.1f %9.3g %8.0f %9.0f %7.2f |",
                  scene.c_str(), r.patches, r.bvh_s, r.raw_rate / 1e6, r.ff_rate / 1e6,
                  r.ff_rate / r.raw_rate, r.ff_s, r.average_s, r.nnz, csr_mb,
                  r.max_rss_kb / 1024.0, r.max_rss_kb / 1024.0 / csr_mb);
      for (int s = 0; s < 3; ++s) {
        char cell[64];
        std::snprintf(cell, sizeof cell, "%.2f (%d)%s", r.solve_s[s], r.iterations[s],
                      r.converged[s] ? "" : " !conv");
        std::printf(" %-22s", cell);
      }
      std::printf("\n");
      std::fflush(stdout);
    }
  }
  return 0;
}
