#pragma once
// The method level: how B is computed for a scene. A method sits above estimator + solver and
// produces the same outputs (per-patch B on a mesh, per-vertex B, images, reports):
//   matrix        mesh the scene (--patches / --max-edge), compute F (--estimator ...), solve
//                 (I - rho F) B = E (--solver ...);
//   hierarchical  link elements of a face and cluster hierarchy adaptively (--epsilon,
//                 --min-area, --link-rays) and solve over the links (geometry/hierarchical).
// The option table (pipeline/option_specs.cpp) names the method of each option only one
// method reads; an option of another method given on the command line is a usage error
// naming the option and the method.

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "geometry/hierarchical/hierarchical.hpp"
#include "pipeline/job.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// One method of the registry.
struct Method {
  std::string name;
  std::string description;
  /// Options that define the problem this method solves (meshing, F, element bounds), and
  /// those that steer how it solves (solver choice and parameters, a precomputed B): the
  /// rows of pipeline/option_specs.cpp whose `method` is this one.
  std::vector<std::string> problem_options;
  std::vector<std::string> solver_options;
  /// Appended to a refusal of another method's option: what this method uses instead.
  std::string instead;
};

/// The registry, in the order `--help` lists it; the first row is the default.
const std::vector<Method>& methods();

/// The registry's names (the choices of --method).
std::vector<std::string> method_names();

/// The registry row of `name` (UsageError if there is none).
const Method& find_method(const std::string& name);

/// The hierarchical method's own options.
struct HierarchicalArgs {
  double epsilon = HierarchicalOptions{}.epsilon;               ///< --epsilon
  std::vector<double> epsilons{HierarchicalOptions{}.epsilon};  ///< --epsilon of `compare` (a list)
  double min_area = HierarchicalOptions{}.min_area;             ///< --min-area (0 = auto)
  int link_rays = HierarchicalOptions{}.link_rays;              ///< --link-rays
};

/// --method and the options of the methods other than matrix.
struct MethodArgs {
  std::string name = "matrix";  ///< --method
  HierarchicalArgs hierarchical;
  /// Which options the front end was given (the CLI sets it; empty = none).
  OptionGiven given;
};

/// True when the option was given (`args.given`).
bool option_given(const MethodArgs& args, const std::string& option);

/// Refuses (UsageError) an option given on the command line that only another method reads.
/// `reference` names a method the command also runs as a reference (compare): its problem
/// options are then accepted, its solver options are still refused.
void check_method_options(const MethodArgs& args, const std::string& reference = "");

/// HierarchicalOptions from the method options, the shared solver options (--tol and
/// --max-iter when given; otherwise the hierarchical defaults, since its stopping rule is a
/// relative change of B, not a residual) and the run options (seed, threads, progress unless
/// --quiet, --max-memory as the hierarchy's memory limit).
HierarchicalOptions make_hierarchical_options(const MethodArgs& args, double epsilon,
                                              const SolveOptions& solve, const RunArgs& run);

/// A command's implementation for each method: {method name, function} rows.
template <class Options>
using MethodTable = std::vector<std::pair<std::string, std::function<int(const Options&)>>>;

/// Runs a command: applies its --quiet / --verbose, refuses the options of other methods
/// (check_method_options with `reference`) and those `selection` does not read
/// (check_options_read), then runs the row of `table` for --method. Every
/// command that offers --method has a row for every registry method: a missing row is a bug
/// (LAMBERT_CHECK), never a silent fallback.
template <class Options>
int run_for_method(const MethodTable<Options>& table, const Options& opts,
                   const Selection& selection, const std::string& reference = "") {
  apply_run_options(opts.run);
  check_method_options(opts.method, reference);
  check_options_read(opts.run, selection);
  for (const auto& [name, run] : table)
    if (name == opts.method.name) return run(opts);
  LAMBERT_CHECK(false, "no implementation of --method " + opts.method.name + " in this command");
  return 0;
}

}  // namespace lambert
