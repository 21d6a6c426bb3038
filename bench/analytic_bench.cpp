// The analytic estimator (geometry/formfactors/analytic.hpp), measured in one run:
//  1. few-polygon cases with exact references (two parallel squares with a centred, a corner
//     and an off-centre mid-plane blocker, perpendicular squares with a fin on the shared
//     edge, the partial-shadow scene): per --tol, the median time of one pair integral over
//     5 runs, its true error, the stated error estimate and their ratio, point factors
//     evaluated and how many were computed from the blockers directly (no cell pattern);
//  2. a closed room with 0..19 boxes (--room-boxes; 101 polygons with 19, one patch per
//     face): full F per --tol, time, the largest |row sum - exact| (1; the floor's is
//     1 - footprint / area, since under the boxes it sees only their backs) and the largest
//     entry difference to the tightest run, next to hybrid at 32 and 1024 samples on the
//     same mesh;
//  3. the crossover against hybrid on the Cornell box at a few patch counts (auto's rule).
// Usage: analytic_bench [--tols 1e-4,1e-6,1e-8] [--room-tols 1e-4] [--room-boxes 19]
//                       [--cornell 50,150] [-j N] [--sections few,room,cornell]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "common/occluded_reference.hpp"
#include "core/timer.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/mesh/mesh.hpp"
#include "io/obj_loader.hpp"

using namespace lambert;

namespace {

std::vector<double> parse_list(const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) out.push_back(std::atof(item.c_str()));
  return out;
}

Polygon3 rect(double x0, double x1, double y0, double y1, double z, bool up) {
  Polygon3 p{{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}};
  if (!up) std::reverse(p.begin(), p.end());
  return p;
}

struct Case {
  const char* name;
  Polygon3 a, b;
  std::vector<Polygon3> blockers;
  double exact;  // G
};

std::vector<Case> cases() {
  const ref::Rect unit{0, 1, 0, 1};
  const PartialShadowGeometry g = partial_shadow_geometry();
  const double c = 0.3;
  const Polygon3 fin{{0, 0, 0}, {0, 1, 0}, {c, 1, c}, {c, 0, c}};
  return {
      {"centred blocker", rect(0, 1, 0, 1, 0, true), rect(0, 1, 0, 1, 1, false),
       {rect(0.25, 0.75, 0.25, 0.75, 0.5, true)},
       ref::parallel_blocked_G(unit, unit, 1.0, {0.25, 0.75, 0.25, 0.75}, 0.5, 32)},
      {"corner blocker", rect(0, 1, 0, 1, 0, true), rect(0, 1, 0, 1, 1, false),
       {rect(0, 0.5, 0, 0.5, 0.5, true)},
       ref::parallel_blocked_G(unit, unit, 1.0, {0, 0.5, 0, 0.5}, 0.5, 32)},
      {"off-centre blocker", rect(0, 1, 0, 1, 0, true), rect(0, 1, 0, 1, 1, false),
       {rect(0.1, 0.45, 0.3, 0.95, 0.3, true)},
       ref::parallel_blocked_G(unit, unit, 1.0, {0.1, 0.45, 0.3, 0.95}, 0.3, 32)},
      {"perpendicular fin", rect(0, 1, 0, 1, 0, true),
       {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}}, {fin}, ref::perpendicular_fin_G(c, 32)},
      {"partial shadow", g.floor, g.light, {g.blocker}, 16.0 * partial_shadow_floor_light_factor(24)},
  };
}

void few_polygons(const std::vector<double>& tols) {
  std::printf("1. few-polygon cases: one pair integral (median of 5 runs)\n");
  std::printf("%-20s %8s %10s %10s %10s %6s %8s %8s %6s\n", "case", "tol", "ms", "error",
              "estimate", "ratio", "points", "direct", "cells");
  for (const Case& c : cases()) {
    for (double tol : tols) {
      std::vector<double> ms;
      ff::AnalyticEstimate e;
      for (int run = 0; run < 5; ++run) {
        Timer t;
        e = ff::analytic_pair_G(c.a, c.b, c.blockers, tol);
        ms.push_back(1e3 * t.seconds());
      }
      std::sort(ms.begin(), ms.end());
      const double err = std::abs(e.G - c.exact);
      std::printf("%-20s %8.0e %10.2f %10.2e %10.2e %6.2f %8lld %8lld %6lld\n", c.name, tol, ms[2],
                  err, e.error, e.error > 0 ? err / e.error : 0.0,
                  static_cast<long long>(e.evaluations),
                  static_cast<long long>(e.direct_evaluations), static_cast<long long>(e.cells));
    }
  }
  std::printf("\n");
}

// A closed 10 x 8 x 3 room (faces inward) with up to 19 boxes standing on the floor (5 faces
// each, outward): 6 + 5 boxes polygons (101 with all 19).
// `footprint` receives the boxes' total floor area (the floor under them sees only their
// backs, so the floor's exact row sum is 1 - footprint / A_floor; every other row's is 1).
Scene furnished_room(int boxes, double& footprint) {
  footprint = 0.0;
  Scene s;
  const Material grey("grey", Eigen::Vector3d::Constant(0.5));
  const double X = 10, Y = 8, Z = 3;
  add_polygon(s, "floor", grey, {{0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0}});
  add_polygon(s, "ceiling", grey, {{0, 0, Z}, {0, Y, Z}, {X, Y, Z}, {X, 0, Z}});
  add_polygon(s, "wall -x", grey, {{0, 0, 0}, {0, Y, 0}, {0, Y, Z}, {0, 0, Z}});
  add_polygon(s, "wall +x", grey, {{X, 0, 0}, {X, 0, Z}, {X, Y, Z}, {X, Y, 0}});
  add_polygon(s, "wall -y", grey, {{0, 0, 0}, {0, 0, Z}, {X, 0, Z}, {X, 0, 0}});
  add_polygon(s, "wall +y", grey, {{0, Y, 0}, {X, Y, 0}, {X, Y, Z}, {0, Y, Z}});
  int n = 0;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j) {
      if (i == 2 && j == 2) continue;  // 19 boxes
      if (n == boxes) return s;
      const double x0 = 0.6 + 1.9 * i + 0.1 * (j % 2), y0 = 0.7 + 1.8 * j + 0.15 * (i % 3);
      const double x1 = x0 + 0.8 + 0.1 * ((i + j) % 3), y1 = y0 + 0.6 + 0.1 * ((i * j) % 4);
      const double h = 0.5 + 0.25 * ((i + 2 * j) % 5);
      const std::string name = "box " + std::to_string(n++);
      footprint += (x1 - x0) * (y1 - y0);
      add_polygon(s, name, grey, {{x0, y0, h}, {x1, y0, h}, {x1, y1, h}, {x0, y1, h}});  // top
      add_polygon(s, name, grey, {{x0, y0, 0}, {x1, y0, 0}, {x1, y0, h}, {x0, y0, h}});  // -y
      add_polygon(s, name, grey, {{x1, y1, 0}, {x0, y1, 0}, {x0, y1, h}, {x1, y1, h}});  // +y
      add_polygon(s, name, grey, {{x0, y1, 0}, {x0, y0, 0}, {x0, y0, h}, {x0, y1, h}});  // -x
      add_polygon(s, name, grey, {{x1, y0, 0}, {x1, y1, 0}, {x1, y1, h}, {x1, y0, h}});  // +x
    }
  return s;
}

// max |row sum - exact row sum| (exact: 1, the floor's 1 - floor_deficit).
double max_row_error(const SparseF& F, const PatchMesh& mesh, double floor_deficit) {
  double worst = 0.0;
  for (Eigen::Index i = 0; i < F.rows(); ++i) {
    const bool floor = mesh.surface_names[mesh.patches[i].surface] == "floor";
    worst = std::max(worst, std::abs(F.row(i).sum() - (floor ? 1.0 - floor_deficit : 1.0)));
  }
  return worst;
}

double max_difference(const SparseF& a, const SparseF& b) {
  return (SparseF(a - b)).coeffs().cwiseAbs().maxCoeff();
}

void room(const std::vector<double>& tols, int boxes, int threads) {
  double footprint = 0.0;
  const PatchMesh mesh = mesh_scene(furnished_room(boxes, footprint), {});
  const double floor_deficit = footprint / 80.0;  // the floor is 10 x 8
  std::printf("2. furnished room: %d boxes, %d polygons, one patch each, -j %d\n", boxes,
              mesh.size(), threads);
  std::printf("%-22s %10s %14s %14s %8s\n", "estimator", "s", "max|rowsum-ex|", "max|F-F_tight|",
              "nnz");
  std::vector<FormFactors> runs;
  std::vector<std::string> names;
  FormFactorOptions o;
  o.run.progress = false;
  o.run.threads = threads;
  o.estimator = "analytic";
  std::vector<double> sorted = tols;
  std::sort(sorted.begin(), sorted.end());  // tightest first: the others compare to it
  for (double tol : sorted) {
    o.analytic.tol = tol;
    runs.push_back(compute_form_factors(mesh, o));
    char buf[64];
    std::snprintf(buf, sizeof buf, "analytic tol %.0e", tol);
    names.push_back(buf);
  }
  o.estimator = "hybrid";
  for (int k : {32, 1024}) {
    o.pair.samples = k;
    runs.push_back(compute_form_factors(mesh, o));
    names.push_back("hybrid " + std::to_string(k) + " samples");
  }
  for (size_t r = 0; r < runs.size(); ++r)
    std::printf("%-22s %10.3f %14.3e %14.3e %8lld  (unverified %lld)\n", names[r].c_str(),
                runs[r].stats.seconds, max_row_error(runs[r].F, mesh, floor_deficit),
                max_difference(runs[r].F, runs[0].F), static_cast<long long>(runs[r].F.nonZeros()),
                static_cast<long long>(runs[r].stats.pairs_unverified));
  std::printf("\n");
}

void cornell(const std::vector<double>& sizes, int threads) {
  const Scene scene = load_obj(builtin_cornell_box_path());
  std::printf("3. crossover on the Cornell box (-j %d): analytic --ff-tol 1e-6 vs hybrid 32 samples\n", threads);
  std::printf("%8s %12s %12s %8s %16s %12s\n", "patches", "analytic s", "hybrid s", "ratio",
              "max|Fa - Fh|", "unverified");
  for (double n : sizes) {
    const PatchMesh mesh = mesh_scene(scene, {0.0, static_cast<std::int64_t>(n)});
    FormFactorOptions o;
    o.run.progress = false;
    o.run.threads = threads;
    o.estimator = "analytic";
    const FormFactors a = compute_form_factors(mesh, o);
    o.estimator = "hybrid";
    const FormFactors h = compute_form_factors(mesh, o);
    std::printf("%8d %12.3f %12.3f %8.2f %16.3e %12lld\n", mesh.size(), a.stats.seconds, h.stats.seconds,
                a.stats.seconds / h.stats.seconds, max_difference(a.F, h.F),
                static_cast<long long>(a.stats.pairs_unverified));
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> tols{1e-4, 1e-6, 1e-8}, room_tols{1e-4}, sizes{50, 150}, boxes{19};
  int threads = 0;
  std::string sections = "few,cornell,room";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--tols") tols = parse_list(v);
    else if (a == "--room-tols") room_tols = parse_list(v);
    else if (a == "--cornell") sizes = parse_list(v);
    else if (a == "--room-boxes")
      boxes = parse_list(v);
    else if (a == "-j") threads = std::atoi(v.c_str());
    else if (a == "--sections") sections = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // figures as they come
  if (sections.find("few") != std::string::npos) few_polygons(tols);
  if (sections.find("cornell") != std::string::npos) cornell(sizes, threads);
  if (sections.find("room") != std::string::npos)
    for (double k : boxes) room(room_tols, static_cast<int>(k), threads);
  return 0;
}
