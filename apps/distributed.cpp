// `formfactors --distributed` and `solve --distributed` (docs/cluster.md):
// every rank loads and meshes the scene and builds its BVH; the pairs (i, j > i) are split
// by rows i over the ranks (balanced_pair_rows), each pair computed once with its serial
// stream; every entry goes to its row's owner (exchange_mirrors), so rank r holds rows
// [rows[r], rows[r + 1]) of exactly the F a single process computes. Rank 0 gathers F to save
// it, or PETSc solves over the row blocks (dist_petsc.cpp). Every stage that can fail on
// one rank runs in dist::collective, so all ranks stop together with rank 0 reporting.
// Built as the module lambert_distributed.so (apps/distributed_entry.hpp): its one export is
// lambert_distributed_entry, at the end.
#include <utility>

#include "apps/cli.hpp"
#include "apps/command_outputs.hpp"
#include "apps/commands.hpp"
#include "apps/dist_mpi.hpp"
#include "apps/dist_petsc.hpp"
#include "apps/distributed_entry.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "io/ff_file.hpp"
#include "pipeline/problem.hpp"

namespace lambert {
namespace {

// Logs and progress on rank 0 only; -j 0 shares the node's cores among its ranks.
RunArgs rank_run_args(const RunArgs& run, const dist::Session& s) {
  RunArgs r = run;
  if (!s.root()) r.quiet = true, r.verbose = false;
  if (r.threads == 0) r.threads = s.default_threads();
  apply_run_options(r);
  return r;
}

// Fails every rank alike (the value compared is the same everywhere after all_equal).
void check_same_mesh(const LoadedScene& scene) {
  if (!dist::all_equal(mesh_hash(scene.mesh)))
    throw dist::Failure{1,
                        "the ranks meshed different scenes: give every rank the same scene "
                        "file and meshing options"};
}

// F's rows of this rank and what it cost.
struct DistributedF {
  dist::RowBlock block;
  FormFactorOptions options;  ///< the settings that made F (no row range)
  FormFactorStats stats;      ///< summed over the ranks (seconds: the slowest rank)
  std::vector<std::int32_t> rows;
  std::vector<double> seconds_per_rank;  ///< each rank's own computation (rank 0 only)
};

// The estimator's settings, "auto" resolved: a pair estimator (auto's gather computes whole
// rows, so auto takes hybrid instead at that size).
FormFactorOptions distributed_ff_options(const FormFactorArgs& args, const RunArgs& run,
                                         std::int32_t n, bool with_stderr) {
  FormFactorOptions o = make_ff_options(args, run);
  o.run.with_stderr = with_stderr;
  if (o.estimator == "auto" && auto_estimator(n, o.analytic.tol_given) == "gather") {
    o.estimator = "hybrid";
    o.estimator_requested = "auto";
    log_info("--distributed: auto picks hybrid (gather, its pick at " + std::to_string(n) +
             " patches, computes whole rows)");
  }
  o = resolve_form_factor_options(o, n);
  if (!is_pair_estimator(o.estimator))
    throw UsageError("--estimator " + o.estimator +
                     " computes whole rows and its reciprocity "
                     "needs whole columns: --distributed takes mc, hybrid or analytic");
  const std::vector<std::string> unused = unused_count_options(args, o.estimator);
  if (!unused.empty())
    throw UsageError(unused.front() + " does not apply: --distributed computes F with " +
                     o.estimator + " at " + std::to_string(n) + " patches");
  return o;
}

DistributedF distributed_form_factors(const dist::Session& s, const LoadedScene& scene,
                                      const FormFactorArgs& args, const RunArgs& run,
                                      bool with_stderr) {
  const std::int32_t n = scene.mesh.size();
  DistributedF out;
  out.rows = dist::row_partition(n, s.size());
  FormFactors partial;
  const Timer timer;
  double compute_seconds = 0.0;  // this rank's own work, before waiting for the others
  dist::collective([&] {
    if (!args.ff_file.empty()) {  // every rank reads the file and keeps its rows
      const FormFactors whole = obtain_form_factors(scene, args, run, with_stderr);
      out.block = dist::slice_rows(whole, out.rows, s.rank());
      out.options = whole.options;
      out.stats = whole.stats;
      return;
    }
    FormFactorOptions o = distributed_ff_options(args, run, n, with_stderr);
    o.subset.row_begin = out.rows[s.rank()];
    o.subset.row_end = out.rows[s.rank() + 1];
    if (o.subset.row_end > o.subset.row_begin) {
      partial = compute_form_factors(scene.mesh, o, &scene_bvh(scene, run.threads));
    } else {  // more ranks than rows
      partial.F.resize(n, n);
      partial.F.makeCompressed();
    }
    o.subset.row_begin = o.subset.row_end = 0;
    out.options = o;
    compute_seconds = timer.seconds();
  });
  if (!args.ff_file.empty()) return out;
  out.block = dist::exchange_mirrors(partial, out.rows);
  FormFactorStats& st = out.stats;
  st.pairs_tested = dist::sum(partial.stats.pairs_tested);
  st.pairs_culled = dist::sum(partial.stats.pairs_culled);
  st.pairs_unverified = dist::sum(partial.stats.pairs_unverified);
  st.unverified_exchange = dist::sum(partial.stats.unverified_exchange);
  st.pairs_short_of_target = dist::sum(partial.stats.pairs_short_of_target);
  st.rays = dist::sum(partial.stats.rays);
  st.seconds = dist::max(timer.seconds());
  out.seconds_per_rank = dist::gather(compute_seconds);
  log_info("form factors: " + std::to_string(n) + " patches over " + std::to_string(s.size()) +
           " ranks, " + format_si(static_cast<double>(dist::sum(out.block.F.nonZeros()))) +
           " entries, " + format_si(static_cast<double>(st.rays)) + " rays in " +
           format_duration(st.seconds));
  return out;
}

// The "distributed" report section: ranks, their rows, time, memory, bytes moved.
Json distributed_json(const dist::Session& s, const DistributedF& f, std::int64_t gather_bytes) {
  const std::int64_t exchanged = dist::sum(f.block.sent_bytes);
  const std::int64_t gathered = dist::sum(gather_bytes);
  const std::vector<double> memory = dist::gather(dist::peak_memory_bytes());
  const std::vector<double> entries = dist::gather(static_cast<double>(f.block.F.nonZeros()));
  if (!s.root()) return Json();
  Json rows = Json::array();
  for (int r = 0; r < s.size(); ++r) rows.push_back({f.rows[r], f.rows[r + 1]});
  return {{"ranks", s.size()},
          {"rows", rows},
          {"entries_per_rank", entries},
          {"form_factor_seconds_per_rank", f.seconds_per_rank},
          {"peak_memory_bytes_per_rank", memory},
          {"exchange_bytes", exchanged},
          {"gather_bytes", gathered}};
}

int formfactors_over_ranks(const FormFactorsOptions& opts) {
  return dist::run_job("", [&](const dist::Session& s) {
    const RunArgs run = rank_run_args(opts.run, s);
    LoadedScene scene;
    const std::string report = formfactors_report_path(opts);
    dist::collective([&] {
      if (!opts.point.empty() || opts.by_surface)
        throw UsageError("--distributed saves F: --point and --by-surface run single-process");
      if (opts.output.empty()) throw UsageError("formfactors: -o/--output is required");
      JobPlan plan = job_plan(run);
      if (s.root()) plan.outputs = {{"-o", opts.output}, {"--report", report}};
      SceneArgs scene_args = opts.scene;  // analytic: whole faces unless asked (formfactors.cpp)
      if ((opts.ff.estimator == "auto" ? auto_estimator(0, opts.ff.given("--ff-tol"))
                                       : opts.ff.estimator) == "analytic")
        scene_args.default_patches = 0;
      scene = load_scene(scene_args, plan);
    });
    check_same_mesh(scene);
    DistributedF f = distributed_form_factors(s, scene, opts.ff, run, opts.with_stderr);
    FormFactors ff;
    std::int64_t gather_bytes = 0;
    dist::gather_rows(f.block, scene.mesh.size(), ff.F, ff.stderr_F, gather_bytes);
    ff.options = f.options;
    ff.stats = f.stats;
    const Json section = distributed_json(s, f, gather_bytes);
    dist::collective([&] {
      if (s.root()) write_formfactors_outputs(opts, scene, ff, report, section);
    });
    return 0;
  });
}

int matrix_over_ranks(const DistributedArgs& dist, const RunArgs& run_args,
                      const FormFactorArgs& ff_args, const SolveOptions& solver,
                      const std::function<LoadedScene(const RunArgs& run, bool root)>& load,
                      const std::function<int(const LoadedScene&, const RadiosityResult&,
                                              const Json& section)>& finish) {
  return dist::run_job(dist.petsc_options, [&](const dist::Session& s) {
    const RunArgs run = rank_run_args(run_args, s);
    LoadedScene scene;
    dist::collective([&] {
      // A solver other than the default was asked for (the same default in solve and run).
      if (solver.solver != SolveOptions().solver ||
          solver.preconditioner != SolveOptions().preconditioner)
        throw UsageError(
            "--solver and --preconditioner pick a single-process solver: with "
            "--distributed the solve is PETSc's (--petsc-options \"-ksp_type bcgs "
            "-pc_type jacobi\", docs/cluster.md)");
      scene = load(run, s.root());
    });
    check_same_mesh(scene);
    DistributedF f = distributed_form_factors(s, scene, ff_args, run, false);
    RadiosityResult r;
    r.solved = true;
    r.ff_options = f.options;
    r.ff_stats = f.stats;
    r.ff_entries = dist::sum(f.block.F.nonZeros());
    r.ff_seconds = f.stats.seconds;
    SolveOptions so = solver;
    so.solver = "petsc";
    dist::PetscSolve solved;
    const std::int32_t n = scene.mesh.size();
    dist::collective([&] {
      const RadiosityProblem problem = make_problem(scene.mesh, f.block.F);
      solved = dist::solve_petsc(problem, f.block, so);
      // I = F (B - E): this rank's rows, then every rank's (other rows of the block are empty).
      const Eigen::MatrixX3d mine = indirect_irradiance(scene.mesh, f.block.F, solved.solution.B);
      r.indirect.resize(n, 3);
      for (int c = 0; c < 3; ++c) {
        const std::vector<double> local(mine.col(c).data() + f.block.begin,
                                        mine.col(c).data() + f.block.end);
        const std::vector<double> all = dist::allgather_rows(local, f.rows);
        r.indirect.col(c) = Eigen::Map<const Eigen::VectorXd>(all.data(), n);
      }
    });
    r.solution = std::move(solved.solution);
    r.B = r.solution.B;
    r.solve_seconds = r.solution.seconds;
    Json section = distributed_json(s, f, 0);
    if (s.root()) {
      section["ghost_columns"] = solved.ghost_columns;
      section["bytes_per_product"] = 8 * solved.ghost_columns;
      section["ksp_type"] = solved.ksp_type;
      section["pc_type"] = solved.pc_type;
      section["petsc_options"] = dist.petsc_options;
    }
    int code = kExitOk;
    dist::collective([&] {
      if (s.root()) code = finish(scene, r, section);
    });
    return s.root()                                      ? code
           : r.solution.status == SolveStatus::Converged ? kExitOk
                                                         : kExitNotConverged;
  });
}

int solve_over_ranks(const SolveCommandOptions& opts) {
  const Timer total;
  double load_seconds = 0.0;
  auto load = [&](const RunArgs& run, bool root) {
    if (opts.method.name != "matrix")
      throw UsageError("--distributed solves with the matrix method (F over the ranks)");
    if (opts.medium.active() || opts.adapt.active())
      throw UsageError("--distributed does not take a participating medium or --adapt yet");
    JobPlan plan = job_plan(run);
    if (root) plan.outputs = {{"-o", opts.output}};
    if (!opts.ff.ff_file.empty()) plan.inputs = {{"--ff", opts.ff.ff_file}};
    LoadedScene scene = load_scene(opts.scene, plan);
    load_seconds = total.seconds();
    return scene;
  };
  auto finish = [&](const LoadedScene& scene, const RadiosityResult& r, const Json& section) {
    MatrixSolveResult result;
    result.options = opts.solve;
    result.options.solver = "petsc";
    result.solution = r.solution;
    result.ff_options = r.ff_options;
    result.load_seconds = load_seconds;
    result.ff_seconds = r.ff_seconds;
    result.nonzeros = r.ff_entries;
    result.distributed = section;
    return write_solve_outputs(opts, scene, result);
  };
  return matrix_over_ranks(opts.dist, opts.run, opts.ff, opts.solve, load, finish);
}

}  // namespace
}  // namespace lambert

extern "C" __attribute__((visibility("default"))) const lambert::DistributedEntry*
lambert_distributed_entry() {
  static const lambert::DistributedEntry entry{
      lambert::kDistributedLayout, &lambert::formfactors_over_ranks, &lambert::solve_over_ranks,
      &lambert::matrix_over_ranks};
  return &entry;
}
