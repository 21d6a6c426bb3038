#include "pipeline/option_scope.hpp"

#include <algorithm>
#include <initializer_list>

#include "core/error.hpp"

namespace lambert {

namespace {

bool is_one_of(const std::string& value, std::initializer_list<const char*> names) {
  return std::any_of(names.begin(), names.end(), [&](const char* n) { return value == n; });
}

// Some solver that runs is one of `names`.
bool runs_solver(const Selection& s, std::initializer_list<const char*> names) {
  return std::any_of(s.solvers.begin(), s.solvers.end(),
                     [&](const std::string& solver) { return is_one_of(solver, names); });
}

// F is computed (not loaded, not replaced by hierarchical links or a given B).
bool computes_f(const Selection& s) { return !s.estimator.empty(); }

// "--estimator E" may read an option of the estimators `names`: E is one of them, or auto
// and one of them is among auto's picks (hybrid, gather, analytic, by the patch count once
// the scene is meshed: that pick is checked then, ff_args.cpp).
bool estimator_may_be(const Selection& s, std::initializer_list<const char*> names) {
  if (!computes_f(s)) return false;
  if (s.estimator == "auto")
    return std::any_of(names.begin(), names.end(), [](const char* n) {
      return is_one_of(n, {"hybrid", "gather", "analytic"});
    });
  return is_one_of(s.estimator, names);
}

// --reciprocity and --symmetrize: the estimators whose F is not reciprocal by construction
// (mc, hybrid and analytic compute each pair once; gather averages by default).
bool averages_pairs(const Selection& s) { return estimator_may_be(s, {"gather", "hemicube"}); }

// --max-iter and --tol: an iterative solver or the hierarchical method runs (direct
// factorises: no iterations, a residual at rounding level whatever the tolerance). The --tol
// of formfactors is --ff-tol's alias: unread_options leaves it to that row.
bool iterates(const Selection& s) {
  return s.method == "hierarchical" ||
         std::any_of(s.solvers.begin(), s.solvers.end(),
                     [](const std::string& v) { return v != "direct"; });
}

// "run --method matrix --estimator hybrid --solver sor": what the command line chose.
std::string describe(const Selection& s) {
  std::string out = s.command + " --method " + s.method;
  if (!s.estimator.empty()) out += " --estimator " + s.estimator;
  if (s.method == "matrix" && s.estimator.empty()) out += " (F given or not computed)";
  if (!s.solvers.empty()) {
    out += s.solvers.size() == 1 ? " --solver " : " --solvers ";
    for (size_t k = 0; k < s.solvers.size(); ++k) out += (k ? "," : "") + s.solvers[k];
  }
  if (!s.shading.empty()) out += " --shading " + s.shading;
  return out;
}

}  // namespace

const std::vector<OptionScope>& option_scopes() {
  static const std::vector<OptionScope> kScopes = {
      // The estimators' own parameters.
      {"--samples", "the pair estimators mc and hybrid",
       [](const Selection& s) {
         return estimator_may_be(s, {"mc", "hybrid"});
       }},
      {"--rays", "the estimator gather",
       [](const Selection& s) { return estimator_may_be(s, {"gather"}); }},
      {"--ff-tol", "the estimator analytic (and auto's choice of it)",
       [](const Selection& s) { return estimator_may_be(s, {"analytic"}); }},
      {"--hemicube-res", "the estimator hemicube",
       [](const Selection& s) { return computes_f(s) && s.estimator == "hemicube"; }},
      // What every estimator's F goes through.
      {"--threshold", "a computed F", computes_f},
      {"--reciprocity", "the estimators gather and hemicube", averages_pairs},
      {"--symmetrize", "the estimators gather and hemicube", averages_pairs},
      {"--specular-rays", "a computed F (the extended form factors through mirrors and glass)",
       computes_f},
      {"--specular-depth",
       "a computed F (extended form factors) and --shading raytrace (camera paths)",
       [](const Selection& s) { return computes_f(s) || s.shading == "raytrace"; }},
      // Random numbers: the Monte Carlo estimators (auto picks hybrid or gather unless
      // --ff-tol makes it analytic), the hemicube's turn about each normal, hierarchical's
      // link rays, a medium's exchange, the pixel jitter of --antialias and the camera paths
      // of --shading raytrace. analytic is deterministic.
      {"--seed",
       "the estimators but analytic, --method hierarchical, a medium, --antialias above 1 "
       "and --shading raytrace",
       [](const Selection& s) {
         return s.method == "hierarchical" || s.medium || s.random_pixels ||
                (computes_f(s) && s.estimator != "analytic");
       }},
      // The solvers' own parameters.
      {"--omega", "the solver sor", [](const Selection& s) { return runs_solver(s, {"sor"}); }},
      {"--preconditioner", "the solvers bicgstab, gmres and cg",
       [](const Selection& s) {
         return runs_solver(s, {"bicgstab", "gmres", "cg"});
       }},
      {"--restart", "the solver gmres (and --distributed's PETSc GMRES)",
       [](const Selection& s) {
         return runs_solver(s, {"gmres", "petsc"});
       }},
      {"--ambient", "the solver southwell",
       [](const Selection& s) { return runs_solver(s, {"southwell"}); }},
      {"--max-iter", "the iterative solvers and --method hierarchical", iterates},
      {"--tol", "the iterative solvers and --method hierarchical", iterates},
  };
  return kScopes;
}

std::vector<std::string> unread_options(const OptionGiven& given, const Selection& selection) {
  std::vector<std::string> out;
  if (!given) return out;
  // (formfactors' --ff-tol is also --tol there: `given` answers for first long names only,
  // so its row is --ff-tol's.)
  for (const OptionScope& row : option_scopes())
    if (given(row.option) && !row.reads(selection)) out.push_back(row.option);
  return out;
}

void check_option_scopes(const OptionGiven& given, const Selection& selection) {
  const std::vector<std::string> unread = unread_options(given, selection);
  if (unread.empty()) return;
  for (const OptionScope& row : option_scopes())
    if (row.option == unread.front())
      throw UsageError(row.option + " does not apply to " + describe(selection) + " (read by " +
                       row.reader + ")");
}

}  // namespace lambert
