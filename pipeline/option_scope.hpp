#pragma once
// Which choices read which options: the rows of pipeline/option_specs.cpp say what reads
// each option (`reads`; none: every choice of the commands that take it). Every command
// checks the options given on its command line against them before any work: an option its
// choices do not read is a usage error (exit 2) naming the option, the choice and what reads
// it, never a silently ignored setting. (pipeline/method.hpp refuses the options of the other
// method first, from the rows' `method`.)

#include <functional>
#include <string>
#include <vector>

namespace lambert {

/// Asks whether the front end was given an option, by its long name ("--omega"). The CLI
/// answers for its command line (apps/options.hpp, option_given_on); empty = none given.
using OptionGiven = std::function<bool(const std::string& long_name)>;

/// What a command line chose: the axes an option's use depends on.
struct Selection {
  std::string command;  ///< "run", "solve", "render", "compare", "formfactors", "heat"
  std::string method = "matrix";
  /// --estimator as given ("auto" included); empty when no F is computed (a loaded --ff,
  /// --method hierarchical, --radiosity).
  std::string estimator;
  /// The solvers that will run: one (--solver; "petsc" with --distributed), several
  /// (compare's --solvers; all by default), or none (formfactors, --method hierarchical,
  /// --radiosity).
  std::vector<std::string> solvers;
  /// The resolved shading of run and render ("gouraud", "flat", "raytrace"); empty elsewhere.
  std::string shading;
  bool medium = false;  ///< a participating medium is given (its exchange is Monte Carlo)
  /// run and render jitter pixel samples (--antialias above 1) or trace camera paths.
  bool random_pixels = false;
};

/// Throws UsageError for the first option `given` that `selection` does not read: "--omega
/// does not apply to --solver jacobi (read by the solver sor)".
void check_option_scopes(const OptionGiven& given, const Selection& selection);

/// The long names of the options `given` that `selection` does not read, in table order
/// (what check_option_scopes refuses; empty when all apply).
std::vector<std::string> unread_options(const OptionGiven& given, const Selection& selection);

}  // namespace lambert
