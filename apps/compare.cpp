#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/plot.hpp"
#include "pipeline/hierarchical_stage.hpp"
#include "pipeline/problem.hpp"
#include "pipeline/solve_stage.hpp"

namespace lambert {
namespace {

// One solver's row of the comparison (channels aggregated).
struct CompareRow {
  std::string solver;
  std::string skipped;  ///< why the solver was not run ("" = it ran)
  RadiositySolution solution;
  int iterations = 0;        ///< summed over channels
  std::int64_t matvecs = 0;  ///< summed over channels
  double residual = 0.0;     ///< worst channel
  double max_diff = 0.0;     ///< max_i,c |B - B_reference|
};

// The solution max_diff is measured against, and its name in reports.
struct Reference {
  Eigen::MatrixX3d B;
  std::string name;
};

// Tolerance of the iterative reference when direct is skipped: 100x tighter than the
// compared solvers', but not below 1e-14, where the residual of an N ~ 1e5 system is at its
// rounding floor (N eps ~ 2e-11 per row sum in the worst case, ~sqrt(N) eps ~ 1e-13 typical).
double reference_tol(double tol) { return std::max(tol * 1e-2, 1e-14); }

CompareRow run_row(const RadiosityProblem& problem, SolveOptions so, const std::string& name) {
  so.solver = name;
  log_info("compare: running " + name);
  CompareRow row;
  row.solver = name;
  row.solution = solve_radiosity(problem, so);
  for (const auto& ch : row.solution.channels) {
    row.iterations += ch.iterations;
    row.matvecs += ch.matvecs;
    row.residual = std::max(row.residual, ch.residual);
  }
  return row;
}

// direct from the rows, or an extra direct solve; when direct is refused (`skip` says why),
// gauss-seidel at reference_tol, or, should it not converge, the converged row with the
// smallest residual.
Reference find_reference(const RadiosityProblem& problem, const SolveOptions& so,
                         const std::vector<CompareRow>& rows, const std::string& skip) {
  for (const auto& r : rows)
    if (r.solver == "direct" && r.skipped.empty()) return {r.solution.B, "direct"};
  if (skip.empty()) {
    log_info("compare: running direct for the reference solution");
    SolveOptions o = so;
    o.solver = "direct";
    return {solve_radiosity(problem, o).B, "direct"};
  }
  SolveOptions o = so;
  o.solver = "gauss-seidel";
  o.tol = reference_tol(so.tol);
  std::ostringstream name;
  name << "gauss-seidel at tol " << o.tol;
  log_info("compare: direct is skipped; running " + name.str() + " for the reference solution");
  const RadiositySolution gs = solve_radiosity(problem, o);
  if (gs.status == SolveStatus::Converged) return {gs.B, name.str()};
  const CompareRow* best = nullptr;
  for (const auto& r : rows)
    if (r.skipped.empty() && r.solution.status == SolveStatus::Converged &&
        (best == nullptr || r.residual < best->residual))
      best = &r;
  if (best == nullptr) {
    log_warn("compare: no solver converged; max_diff is against " + name.str() +
             ", which did not converge either");
    return {gs.B, name.str() + " (not converged)"};
  }
  log_warn("compare: " + name.str() + " did not converge; the reference is " + best->solver +
           ", the converged solver with the smallest residual");
  return {best->solution.B, best->solver};
}

// The channel the plot shows: the one with the most emitted power.
int plot_channel(const RadiosityProblem& p) {
  int best = 0;
  for (int c = 1; c < 3; ++c)
    if (p.area.dot(p.emission.col(c)) > p.area.dot(p.emission.col(best))) best = c;
  return best;
}

void write_table_csv(const std::string& path, const std::vector<CompareRow>& rows,
                     const std::string& reference) {
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "solver,status,iterations,matvecs,seconds,residual,max_diff,reference\n";
    for (const auto& r : rows) {
      if (!r.skipped.empty()) {
        out << r.solver << ",skipped,,,,,," << csv_field(r.skipped) << '\n';
        continue;
      }
      out << r.solver << ',' << to_string(r.solution.status) << ',' << r.iterations << ','
          << r.matvecs << ',' << csv_number(r.solution.seconds) << ',' << csv_number(r.residual)
          << ',' << csv_number(r.max_diff) << ',' << csv_field(reference) << '\n';
    }
  });
}

void write_history_csv(const std::string& path, const std::vector<CompareRow>& rows) {
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "solver,channel,iteration,seconds,residual\n";
    for (const auto& r : rows)
      for (int c = 0; c < 3 && r.skipped.empty(); ++c) {
        const ChannelReport& ch = r.solution.channels[c];
        for (size_t k = 0; k < ch.residual_history.size(); ++k)
          out << r.solver << ',' << channel_name(c) << ',' << ch.history_iteration[k] << ','
              << csv_number(ch.time_history[k]) << ',' << csv_number(ch.residual_history[k])
              << '\n';
      }
  });
}

std::vector<Plot> convergence_plots(const std::vector<CompareRow>& rows, int c, double tol) {
  Plot by_iteration, by_time;
  const std::string ch = std::string(" (channel ") + channel_name(c) + ", tol " + [&] {
    std::ostringstream s;
    s << tol;
    return s.str();
  }() + ")";
  by_iteration.title = "residual vs iteration" + ch;
  by_iteration.x_label = "iteration";
  by_time.title = "residual vs time" + ch;
  by_time.x_label = "seconds";
  by_iteration.y_label = by_time.y_label = "||E - K B|| / ||E||";
  for (const auto& r : rows) {
    if (!r.skipped.empty()) continue;
    const ChannelReport& rep = r.solution.channels[c];
    PlotSeries it{r.solver, {}, rep.residual_history};
    it.x.assign(rep.history_iteration.begin(), rep.history_iteration.end());
    by_iteration.series.push_back(it);
    by_time.series.push_back({r.solver, rep.time_history, rep.residual_history});
  }
  return {by_iteration, by_time};
}

// --method matrix: every solver (--solvers) on one F.
int compare_matrix(const CompareOptions& opts) {
  const std::string base = output_prefix(opts.output, "compare");
  const std::string table = base + "_table.csv", history = base + "_history.csv";
  const std::string svg = base + "_convergence.svg";
  JobPlan plan = job_plan(opts.run);
  plan.outputs = {{"-o", table}, {"-o", history}, {"-o", svg}};
  plan_form_factors(plan, opts.ff, opts.run);
  const std::shared_ptr<const Medium> medium = make_medium(opts.medium);
  plan.medium = medium.get();
  plan.medium_rays = opts.medium.rays;
  const LoadedScene loaded = load_scene(opts.scene, plan);
  if (medium) check_medium_scene(loaded.mesh, nullptr);
  FormFactors ff = obtain_form_factors(loaded, opts.ff, opts.run, false, medium.get());
  // With a medium the solvers compare on the extended system (patches, then zones).
  Zones zones;
  if (medium) {
    zones = make_zones(*medium);
    if (ff.options.contents.medium_zones == 0) {
      warn_about_lighting(loaded.mesh, ff.F);
      check_closed_lossless(loaded.mesh, ff);
      ff = medium_form_factors(loaded, ff, *medium, zones, opts.medium, opts.run);
    }
    log_info("compare: " + std::to_string(loaded.mesh.size()) + " patches + " +
             std::to_string(zones.size()) + " medium zones");
  }
  const RadiosityProblem problem =
      medium ? make_extended_problem(loaded.mesh, ff.F, zones.albedo, zones.emission, zones.area)
             : make_lit_problem(loaded, ff, opts.run.seed, opts.run.threads, nullptr);
  if (!medium) {
    warn_about_lighting(loaded.mesh, ff.F);
    check_closed_lossless(loaded.mesh, ff);
  }
  std::vector<std::string> names = opts.solvers.empty() ? solver_names() : opts.solvers;
  // Drop repeated names, keeping the first occurrence's order.
  std::vector<std::string> unique_names;
  for (const auto& n : names)
    if (std::find(unique_names.begin(), unique_names.end(), n) == unique_names.end())
      unique_names.push_back(n);
  names = unique_names;

  SolveOptions so = opts.solve;
  so.threads = opts.run.threads;
  set_memory_limit(so, opts.run.max_memory);
  // direct above the job's memory limit is skipped, not refused: the others still compare.
  const std::string skip = direct_refusal(problem.F->size(), problem.F->entries(),
                                          so.memory_limit, so.memory_limit_source);
  std::vector<CompareRow> rows;
  for (const auto& name : names) {
    if (name == "direct" && !skip.empty()) {
      log_warn("compare: skipping " + skip);
      CompareRow row;
      row.solver = name;
      row.skipped = skip;
      rows.push_back(std::move(row));
      continue;
    }
    rows.push_back(run_row(problem, so, name));
  }
  const Reference reference = find_reference(problem, so, rows, skip);
  for (auto& r : rows)
    if (r.skipped.empty()) r.max_diff = (r.solution.B - reference.B).cwiseAbs().maxCoeff();

  std::printf("%d patches%s, %lld form factors, tol %g, max-iter %d\n", loaded.mesh.size(),
              medium ? (" + " + std::to_string(zones.size()) + " medium zones").c_str() : "",
              static_cast<long long>(ff.F.nonZeros()), opts.solve.tol, opts.solve.max_iterations);
  std::printf("%-13s %-15s %10s %10s %10s %12s %15s\n", "solver", "status", "iterations",
              "mat-vecs", "time (s)", "residual", "max |B-ref|");
  bool all_converged = true;
  for (const auto& r : rows) {
    if (!r.skipped.empty()) {
      std::printf("%-13s %-15s (%s)\n", r.solver.c_str(), "skipped", r.skipped.c_str());
      continue;
    }
    std::printf("%-13s %-15s %10d %10lld %10.4f %12.3e %15.3e\n", r.solver.c_str(),
                to_string(r.solution.status), r.iterations, static_cast<long long>(r.matvecs),
                r.solution.seconds, r.residual, r.max_diff);
    all_converged = all_converged && r.solution.status == SolveStatus::Converged;
  }
  std::printf("reference for max |B-ref|: %s\n", reference.name.c_str());
  write_table_csv(table, rows, reference.name);
  write_history_csv(history, rows);
  const auto plots = convergence_plots(rows, plot_channel(problem), opts.solve.tol);
  write_plots_svg(svg, plots);
  std::printf("wrote %s, %s, %s (PNG: python3 -m lambert.plot compare %s)\n", table.c_str(),
              history.c_str(), svg.c_str(), opts.output.c_str());
  if (!all_converged) {
    log_warn("some solvers did not converge within --max-iter; results were written anyway");
    return kExitNotConverged;
  }
  return kExitOk;
}

// One hierarchical run of the comparison and its per-surface differences to the reference.
struct HierarchicalRow {
  double epsilon = 0.0;
  HierarchicalRun run;
  std::vector<SurfaceRadiosity> surfaces;
  std::vector<Eigen::Vector3d> diff;  ///< per surface, |B_h - B_ref| / B_ref per channel (NaN:
                                      ///< the reference is 0 there)
  double max_diff = 0.0;              ///< over surfaces with area and channels with B_ref > 0
  std::string worst;                  ///< the surface of max_diff
};

// Per-surface relative differences of `row` against the reference averages.
void surface_differences(HierarchicalRow& row, const std::vector<SurfaceRadiosity>& ref) {
  row.surfaces = surface_averages(row.run.loaded.mesh, row.run.B);
  row.diff.assign(ref.size(), Eigen::Vector3d::Constant(std::nan("")));
  for (size_t s = 0; s < ref.size(); ++s) {
    if (ref[s].area <= 0.0) continue;
    for (int c = 0; c < 3; ++c) {
      if (ref[s].average[c] <= 0.0) continue;
      const double d = std::abs(row.surfaces[s].average[c] - ref[s].average[c]) / ref[s].average[c];
      row.diff[s][c] = d;
      if (d > row.max_diff || row.worst.empty()) {
        row.max_diff = std::max(row.max_diff, d);
        row.worst = ref[s].name;
      }
    }
  }
}

void write_hierarchical_table(const std::string& path, const std::vector<HierarchicalRow>& rows,
                              std::int32_t patches, std::int64_t entries, std::int64_t rays,
                              double seconds, const std::string& reference) {
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "method,epsilon,patches,interactions,rays,seconds,status,max_surface_diff,"
           "worst_surface,reference\n";
    out << "matrix,," << patches << ',' << entries << ',' << rays << ',' << csv_number(seconds)
        << ",reference,,," << csv_field(reference) << '\n';
    for (const auto& r : rows) {
      const HierarchicalStats& st = r.run.stats;
      out << "hierarchical," << csv_number(r.epsilon) << ',' << st.leaves << ',' << st.links << ','
          << st.rays << ',' << csv_number(r.run.seconds) << ','
          << to_string(hierarchical_status(st)) << ',' << csv_number(r.max_diff) << ','
          << csv_field(r.worst) << ',' << csv_field(reference) << '\n';
    }
  });
}

void write_surfaces_csv(const std::string& path, const std::vector<SurfaceRadiosity>& ref,
                        const std::vector<HierarchicalRow>& rows) {
  const auto cell = [](double d) { return std::isnan(d) ? std::string() : csv_number(d); };
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "surface,area,method,epsilon,R,G,B,diff_R,diff_G,diff_B\n";
    for (size_t s = 0; s < ref.size(); ++s) {
      const auto& a = ref[s].average;
      out << csv_field(ref[s].name) << ',' << csv_number(ref[s].area) << ",matrix,,"
          << csv_number(a[0]) << ',' << csv_number(a[1]) << ',' << csv_number(a[2]) << ",,,\n";
      for (const auto& r : rows) {
        const auto& h = r.surfaces[s].average;
        out << csv_field(ref[s].name) << ',' << csv_number(ref[s].area) << ",hierarchical,"
            << csv_number(r.epsilon) << ',' << csv_number(h[0]) << ',' << csv_number(h[1]) << ','
            << csv_number(h[2]) << ',' << cell(r.diff[s][0]) << ',' << cell(r.diff[s][1]) << ','
            << cell(r.diff[s][2]) << '\n';
      }
    }
  });
}

// --method hierarchical: one hierarchical run per --epsilon against the matrix reference (F
// from the form-factor options on the --patches mesh, solved by direct, or gauss-seidel at
// a tight tolerance when direct does not fit), compared per surface (the meshes differ).
int compare_hierarchical(const CompareOptions& opts) {
  // The matrix reference's options are accepted here, but a medium has no hierarchical side.
  if (const std::string o = first_medium_option_given(opts.medium); !o.empty())
    throw UsageError(o +
                     " is not available with --method hierarchical (a participating "
                     "medium is solved by the matrix method only)");
  const std::string base = output_prefix(opts.output, "compare");
  const std::string table = base + "_table.csv", surfaces_csv = base + "_surfaces.csv";
  JobPlan plan = job_plan(opts.run);
  plan.outputs = {{"-o", table}, {"-o", surfaces_csv}};
  plan_form_factors(plan, opts.ff, opts.run);
  const LoadedScene loaded = load_scene(opts.scene, plan);
  const Timer ff_timer;
  const FormFactors ff = obtain_form_factors(loaded, opts.ff, opts.run);
  const RadiosityProblem problem = make_problem(loaded.mesh, ff);
  warn_about_lighting(loaded.mesh, ff.F);
  check_closed_lossless(loaded.mesh, ff);
  // The reference's own stopping rule (the default solver tolerance): --tol and --max-iter
  // steer the hierarchical runs.
  SolveOptions so;
  so.threads = opts.run.threads;
  set_memory_limit(so, opts.run.max_memory);
  const std::string skip = direct_refusal(problem.F->size(), problem.F->entries(), so.memory_limit,
                                          so.memory_limit_source);
  if (!skip.empty()) log_warn("compare: skipping " + skip);
  const Reference reference = find_reference(problem, so, {}, skip);
  const double reference_seconds = ff_timer.seconds();
  const std::vector<SurfaceRadiosity> ref = surface_averages(loaded.mesh, reference.B);

  std::vector<double> epsilons;
  for (double e : opts.method.hierarchical.epsilons)
    if (std::find(epsilons.begin(), epsilons.end(), e) == epsilons.end()) epsilons.push_back(e);
  std::vector<HierarchicalRow> rows;
  for (double e : epsilons) {
    log_info("compare: running hierarchical at epsilon " + csv_number(e));
    HierarchicalRow row;
    row.epsilon = e;
    row.run = solve_scene_hierarchical(
        loaded.scene, make_hierarchical_options(opts.method, e, opts.solve, opts.run));
    surface_differences(row, ref);
    rows.push_back(std::move(row));
  }

  std::printf("reference: matrix, %d patches, %lld form factors (%s), %s; %.3f s\n",
              loaded.mesh.size(), static_cast<long long>(ff.F.nonZeros()),
              ff_settings_text(ff.options, opts.ff.ff_file).c_str(), reference.name.c_str(),
              reference_seconds);
  std::printf("%-10s %-15s %10s %12s %12s %10s %12s  %s\n", "epsilon", "status", "leaves", "links",
              "rays", "time (s)", "max surface", "worst surface");
  bool all_converged = true;
  for (const auto& r : rows) {
    const HierarchicalStats& st = r.run.stats;
    std::printf("%-10.3g %-15s %10lld %12lld %12lld %10.3f %12.3e  %s\n", r.epsilon,
                to_string(hierarchical_status(st)), static_cast<long long>(st.leaves),
                static_cast<long long>(st.links), static_cast<long long>(st.rays), r.run.seconds,
                r.max_diff, r.worst.c_str());
    all_converged = all_converged && st.converged;
  }
  std::printf(
      "max surface: max over surfaces and channels of |B_h - B_ref| / B_ref of the "
      "area-weighted surface averages\n");
  write_hierarchical_table(table, rows, loaded.mesh.size(), ff.F.nonZeros(), ff.stats.rays,
                           reference_seconds, "matrix " + reference.name);
  write_surfaces_csv(surfaces_csv, ref, rows);
  std::printf("wrote %s, %s\n", table.c_str(), surfaces_csv.c_str());
  if (!all_converged) {
    log_warn(
        "some hierarchical runs did not converge within --max-iter; results were written "
        "anyway");
    return kExitNotConverged;
  }
  return kExitOk;
}

}  // namespace

CLI::App* add_compare_command(CLI::App& app, CompareOptions& opts) {
  auto* cmd = app.add_subcommand(
      "compare", "Run several solvers on one system: table, histories and convergence plots");
  opts.scene.default_patches = 2000;
  opts.scene.require_emitter = true;  // B from E: a scene where nothing emits is refused
  add_scene_options(cmd, opts.scene);
  add_method_options(cmd, opts.method, true);
  add_ff_options(cmd, opts.ff);
  add_solve_options(cmd, opts.solve, false);
  add_declared(cmd, "--solvers", opts.solvers);
  add_declared(cmd, "-o,--output", opts.output);
  add_run_options(cmd, opts.run);
  add_medium_options(cmd, opts.medium);
  return cmd;
}

int run_compare(const CompareOptions& opts) {
  static const MethodTable<CompareOptions> kMethods = {{"matrix", compare_matrix},
                                                       {"hierarchical", compare_hierarchical}};
  // The hierarchical comparison runs a matrix reference: its problem options set it up.
  // Its matrix reference computes F (F + direct): the estimator's options apply, no solver's.
  Selection selection{"compare", opts.method.name,    selected_estimator(opts.ff), {},
                      "",        opts.medium.active()};
  if (opts.method.name == "matrix")
    selection.solvers = opts.solvers.empty() ? solver_names() : opts.solvers;
  return run_for_method(kMethods, opts, selection,
                        opts.method.name == "hierarchical" ? "matrix" : "");
}

}  // namespace lambert
