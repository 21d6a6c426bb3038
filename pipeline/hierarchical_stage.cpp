#include "pipeline/hierarchical_stage.hpp"

#include <sstream>
#include <utility>

#include "core/log.hpp"
#include "core/memory.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/analysis.hpp"
#include "pipeline/problem.hpp"

namespace lambert {
namespace {

std::string number(double x) {
  std::ostringstream ss;
  ss << x;
  return ss.str();
}

}  // namespace

HierarchicalRun solve_scene_hierarchical(Scene scene, const HierarchicalOptions& options) {
  const Timer timer;
  HierarchicalResult result = solve_hierarchical(scene, options);
  HierarchicalRun run;
  run.seconds = timer.seconds();
  run.loaded.scene = std::move(scene);
  run.loaded.mesh = std::move(result.mesh);
  run.loaded.max_edge = 0.0;
  run.B = std::move(result.B);
  run.error_bound = std::move(result.error_bound);
  run.stats = result.stats;
  run.options = options;
  const HierarchicalStats& st = run.stats;
  log_info("hierarchical: " + std::to_string(st.leaves) + " leaves (" + std::to_string(st.faces) +
           " faces, " + std::to_string(st.elements) + " elements, " + std::to_string(st.clusters) +
           " clusters), " + format_si(static_cast<double>(st.links)) + " links (" +
           format_si(static_cast<double>(st.cluster_links)) + " with a cluster), " +
           format_si(static_cast<double>(st.rays)) + " rays, " + std::to_string(st.passes) +
           " passes, " + std::to_string(st.iterations) + " sweeps in " +
           format_duration(run.seconds) + ", " + format_bytes(st.memory_bytes));
  if (!st.blind_emitters.empty()) {
    LightingProblems problems;
    problems.blind_emitters = st.blind_emitters;
    for (const std::string& line : lighting_warnings(run.loaded.mesh, problems)) log_warn(line);
  }
  if (!st.converged)
    log_warn("the hierarchical sweeps did not converge (last relative change " + number(st.change) +
             " > tol " + number(options.tol) + " after " + std::to_string(st.iterations) +
             " sweeps); results are written anyway");
  return run;
}

SolveStatus hierarchical_status(const HierarchicalStats& stats) {
  return stats.converged ? SolveStatus::Converged : SolveStatus::MaxIterations;
}

Json hierarchical_json(const HierarchicalRun& run) {
  const HierarchicalOptions& o = run.options;
  const HierarchicalStats& st = run.stats;
  Json bounds = Json::array();
  for (const SurfaceRadiosity& b :
       surface_averages(run.loaded.mesh, run.error_bound.replicate(1, 3)))
    bounds.push_back({{"name", b.name}, {"error_bound", b.average[0]}});
  return {{"status", to_string(hierarchical_status(st))},
          {"options",
           {{"epsilon", o.epsilon},
            {"min_area", o.min_area},
            {"link_rays", o.link_rays},
            {"tol", o.tol},
            {"max_iterations", o.max_iterations},
            {"max_passes", o.max_passes},
            {"seed", o.seed},
            {"memory_limit", o.memory_limit}}},
          {"faces", st.faces},
          {"elements", st.elements},
          {"clusters", st.clusters},
          {"leaves", st.leaves},
          {"links", st.links},
          {"cluster_links", st.cluster_links},
          {"rays", st.rays},
          {"passes", st.passes},
          {"iterations", st.iterations},
          {"converged", st.converged},
          {"change", st.change},
          {"memory_bytes", st.memory_bytes},
          {"min_area", st.min_area},
          {"seconds",
           {{"build", st.build_seconds},
            {"refine", st.refine_seconds},
            {"solve", st.solve_seconds},
            {"total", run.seconds}}},
          {"surface_error_bounds", bounds}};
}

Json hierarchical_energy_json(const HierarchicalEnergy& e) {
  return {{"emitted", e.emitted},
          {"absorbed", e.absorbed},
          {"escaped", e.escaped},
          {"relative_imbalance", e.relative_imbalance}};
}

std::string hierarchical_settings_text(const HierarchicalRun& run) {
  const HierarchicalOptions& o = run.options;
  std::ostringstream ss;
  ss << "method=hierarchical leaves=" << run.loaded.mesh.size() << " epsilon=" << o.epsilon
     << " min_area=" << run.stats.min_area << " link_rays=" << o.link_rays << " tol=" << o.tol
     << " seed=" << o.seed;
  return ss.str();
}

}  // namespace lambert
