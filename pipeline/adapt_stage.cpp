#include "pipeline/adapt_stage.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "geometry/mesh/adapt.hpp"
#include "pipeline/daylight_stage.hpp"
#include "pipeline/problem.hpp"

namespace lambert {

namespace {

double estimated_error(const PatchMesh& mesh, const std::vector<double>& e) {
  double area = 0;
  for (const auto& p : mesh.patches) area += p.area;
  return area > 0 ? std::accumulate(e.begin(), e.end(), 0.0) / area : 0.0;
}

RadiositySolution solve_on(const LoadedScene& scene, const FormFactors& ff, SolveOptions so,
                           const RunArgs& run) {
  const RadiosityProblem problem = make_lit_problem(scene, ff, run.seed, run.threads, nullptr);
  return solve_radiosity(problem, so);
}

}  // namespace

std::vector<AdaptRound> adapt_scene(LoadedScene& scene, const FormFactorArgs& ff_args,
                                    const SolveOptions& solver, const RunArgs& run,
                                    const AdaptArgs& adapt, FormFactors& ff,
                                    RadiositySolution& solution) {
  if (!ff_args.ff_file.empty())
    throw UsageError("--adapt and --adapt-patches compute F as they refine: they cannot use --ff");
  const int rounds = adapt.rounds > 0 ? adapt.rounds : kAdaptMaxRounds;
  // Bisection needs triangles: quads are split first (the round-0 mesh).
  scene.mesh = triangulate_quads(scene.mesh).mesh;
  scene.adapted = true;
  scene.bvh.reset();
  FormFactorOptions fo =
      resolve_form_factor_options(make_ff_options(ff_args, run), scene.mesh.size());
  SolveOptions so = solver;
  so.threads = run.threads;
  std::vector<AdaptRound> out;
  Timer timer;
  ff = compute_form_factors(scene.mesh, fo, &scene_bvh(scene, run.threads));
  check_closed_lossless(scene.mesh, ff);  // refinement keeps a closed lossless set closed
  solution = solve_on(scene, ff, so, run);
  std::int64_t changed_now = scene.mesh.size();  // patches whose factors this round computed
  for (int round = 0;; ++round) {
    // The error of the field that is shaded: on a discontinuity mesh exact direct light at
    // the vertices (interpolation of H_d, jumps of the indirect part), otherwise the
    // interpolated B (its mismatch with the constants, not their jumps: refining by jumps
    // spent the patches on slopes a linear interpolant already follows, and the Gouraud
    // field of the adapted mesh erred twice as much as uniform meshing's, issue 35 item 7).
    const std::vector<double> e =
        scene.discontinuity ? exact_direct_patch_errors(
                                  scene.scene, scene.mesh,
                                  indirect_irradiance(scene.mesh, ff.F, solution.B), run.threads)
                            : field_patch_errors(scene.mesh, solution.B);
    AdaptRound r;
    r.round = round;
    r.patches = scene.mesh.size();
    r.changed = changed_now;
    r.estimated_error = estimated_error(scene.mesh, e);
    r.seconds = timer.seconds();
    r.solve_seconds = solution.seconds;
    r.rays = ff.stats.rays;
    out.push_back(r);
    log_info("adapt: round " + std::to_string(round) + ": " + std::to_string(r.patches) +
             " patches, estimated error " + std::to_string(r.estimated_error) + " W/m^2, " +
             std::to_string(r.seconds) + " s");
    if (round >= rounds || (adapt.patches > 0 && scene.mesh.size() >= adapt.patches)) break;
    // Mark the worst patches: a fifth of them, fewer when the budget is near (a bisection
    // adds about two patches with its conformity closure).
    std::vector<std::int32_t> order(scene.mesh.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) { return e[a] > e[b]; });
    auto marks =
        static_cast<std::int64_t>(std::ceil(kAdaptFraction * static_cast<double>(order.size())));
    if (adapt.patches > 0)
      marks = std::min(marks, std::max<std::int64_t>(1, (adapt.patches - scene.mesh.size()) / 2));
    std::vector<char> marked(scene.mesh.size(), 0);
    std::int64_t count = 0;
    for (std::int64_t k = 0; k < marks && e[order[k]] > 0; ++k, ++count) marked[order[k]] = 1;
    if (count == 0) break;  // nothing varies: the solution is as good as this mesh can do
    timer.reset();
    RefinedMesh ref = refine_marked(scene.mesh, marked);
    std::vector<std::int32_t> origin(ref.origin.size());
    std::int64_t changed = 0;
    Eigen::MatrixX3d guess(ref.mesh.size(), 3);
    for (size_t i = 0; i < origin.size(); ++i) {
      origin[i] = ref.changed[i] ? -1 : ref.origin[i];
      changed += ref.changed[i];
      guess.row(static_cast<Eigen::Index>(i)) = solution.B.row(ref.origin[i]);
    }
    scene.mesh = std::move(ref.mesh);
    scene.bvh.reset();
    ff = update_form_factors(scene.mesh, origin, ff.F, fo, &scene_bvh(scene, run.threads));
    so.initial_guess = guess;
    solution = solve_on(scene, ff, so, run);
    changed_now = changed;
  }
  return out;
}

Json adapt_json(const std::vector<AdaptRound>& rounds) {
  Json a = Json::array();
  for (const auto& r : rounds)
    a.push_back({{"round", r.round},
                 {"patches", r.patches},
                 {"changed", r.changed},
                 {"estimated_error", r.estimated_error},
                 {"seconds", r.seconds},
                 {"rays", r.rays}});
  return a;
}

}  // namespace lambert
