#include "pipeline/option_specs.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/hierarchical/hierarchical.hpp"
#include "pipeline/ff_stage.hpp"
#include "pipeline/job.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {
namespace {

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

OptionSpec integer(std::string name, std::string keyword, double lo, double hi, int default_value,
                   std::string doc) {
  OptionSpec s;
  s.name = std::move(name);
  s.keyword = std::move(keyword);
  s.kind = OptionKind::Integer;
  s.lo = lo;
  s.hi = hi;
  s.default_text = std::to_string(default_value);
  s.doc = std::move(doc);
  return s;
}

OptionSpec real(std::string name, std::string keyword, double lo, double hi, double default_value,
                std::string doc, bool open_lo = false, bool open_hi = false) {
  OptionSpec s;
  s.name = std::move(name);
  s.keyword = std::move(keyword);
  s.kind = OptionKind::Real;
  s.lo = lo;
  s.hi = hi;
  s.open_lo = open_lo;
  s.open_hi = open_hi;
  s.default_text = number_text(default_value);
  s.doc = std::move(doc);
  return s;
}

OptionSpec choice(std::string name, std::string keyword, std::vector<std::string> choices,
                  std::string default_value, std::string doc) {
  OptionSpec s;
  s.name = std::move(name);
  s.keyword = std::move(keyword);
  s.kind = OptionKind::Choice;
  s.choices = std::move(choices);
  s.default_text = std::move(default_value);
  s.doc = std::move(doc);
  return s;
}

std::vector<OptionSpec> make_specs() {
  const FormFactorArgs ff;
  const SolveOptions so;
  const HierarchicalOptions hierarchical;
  std::vector<OptionSpec> t;
  // Form factors (pipeline/ff_stage.hpp).
  t.push_back(choice("--estimator", "estimator", form_factor_estimator_choices(), ff.estimator,
                     "Form-factor estimator (auto: hybrid below " +
                         std::to_string(kAutoGatherPatches) + " patches, gather from there)"));
  t.push_back(integer("--samples", "samples", 1, 1 << 20, ff.samples,
                      "Sample pairs (rays) per patch pair (pair estimators mc, hybrid)"));
  t.push_back(integer("--rays", "rays", 1, 1 << 24, ff.rays, "Rays per patch (estimator gather)"));
  t.push_back(real("--ff-tol", "tol", 1e-15, 1.0, ff.tol,
                   "Absolute error target of every form factor (estimator analytic)"));
  t.push_back(real("--threshold", "threshold", 0.0, 1.0, ff.threshold,
                   "Drop form factors below this value"));
  t.push_back(integer("--hemicube-res", "hemicube_resolution", 4, 8192, ff.hemicube_resolution,
                      "Hemicube top-face resolution (estimator hemicube)"));
  t.push_back(choice("--reciprocity", "reciprocity", {"auto", "none", "average"}, ff.reciprocity,
                     "Replace A_i F_ij and A_j F_ji by their mean: none, average, or auto "
                     "(average for gather, none for the others)"));
  t.push_back(integer("--specular-depth", "", 0, 64, ff.specular_depth,
                      "Specular bounces a ray follows through mirrors and glass (extended form "
                      "factors, ray-traced shading); 0 = specular surfaces only receive and "
                      "block"));
  t.push_back(integer("--specular-rays", "", 1, 1 << 24, ff.specular_rays,
                      "Rays per patch that trace the specular paths of the extended form "
                      "factors (scenes with mirrors or glass)"));
  // Solvers (solvers/radiosity.hpp).
  t.push_back(
      choice("--solver", "solver", solver_names(), so.solver, "Solver (see `lambert solvers`)"));
  std::ostringstream tol_doc, iter_doc;
  tol_doc << "Stop when ||E - K B||_2 / ||E||_2 <= tol (--method hierarchical: when the largest "
             "change of a leaf's B over the largest B <= tol; its default "
          << hierarchical.tol << ")";
  iter_doc << "Iteration limit per channel (--method hierarchical: sweeps per refinement pass; "
              "its default "
           << hierarchical.max_iterations << ")";
  t.push_back(real("--tol", "tol", 1e-16, 0.5, so.tol, tol_doc.str()));
  t.push_back(
      integer("--max-iter", "max_iterations", 1, 100000000, so.max_iterations, iter_doc.str()));
  t.push_back(real("--omega", "omega", 1e-3, 1.999, so.omega, "SOR relaxation factor, in (0, 2)"));
  t.push_back(choice("--preconditioner", "preconditioner", {"none", "diagonal", "ilut"},
                     so.preconditioner, "bicgstab/gmres/cg preconditioner"));
  t.push_back(integer("--restart", "restart", 1, 10000, so.restart, "GMRES restart length"));
  return t;
}

}  // namespace

std::string number_text(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

const std::vector<OptionSpec>& option_specs() {
  static const std::vector<OptionSpec> kSpecs = make_specs();
  return kSpecs;
}

const OptionSpec& option_spec(const std::string& name) {
  for (const OptionSpec& s : option_specs())
    if (s.name == name) return s;
  LAMBERT_CHECK(false, "no option_specs() row for " + name);
  return option_specs().front();
}

std::string accepted_text(const OptionSpec& spec) {
  switch (spec.kind) {
    case OptionKind::Integer:
      return "an integer in [" + std::to_string(static_cast<long long>(spec.lo)) + ", " +
             std::to_string(static_cast<long long>(spec.hi)) + "]";
    case OptionKind::Real:
      return "a number in " + std::string(spec.open_lo ? "(" : "[") + number_text(spec.lo) + ", " +
             number_text(spec.hi) + (spec.open_hi ? ")" : "]");
    case OptionKind::Choice:
      return "one of " + join(spec.choices);
  }
  return "";
}

std::string option_value_error(const OptionSpec& spec, const std::string& text) {
  const std::string refusal = "'" + text + "' is not " + accepted_text(spec);
  if (spec.kind == OptionKind::Choice) {
    for (const auto& c : spec.choices)
      if (c == text) return "";
    return refusal;
  }
  double x = 0.0;
  if (!parse_finite_number(text, x)) return refusal;
  if (spec.kind == OptionKind::Integer && x != std::floor(x)) return refusal;
  const bool above = spec.open_lo ? x > spec.lo : x >= spec.lo;
  const bool below = spec.open_hi ? x < spec.hi : x <= spec.hi;
  return above && below ? "" : refusal;
}

void check_option_value(const OptionSpec& spec, double value, const std::string& as) {
  const bool above = spec.open_lo ? value > spec.lo : value >= spec.lo;
  const bool below = spec.open_hi ? value < spec.hi : value <= spec.hi;
  if (std::isfinite(value) && above && below &&
      (spec.kind != OptionKind::Integer || value == std::floor(value)))
    return;
  throw UsageError(as + ": " + number_text(value) + " is not " + accepted_text(spec));
}

void check_option_choice(const OptionSpec& spec, const std::string& value, const std::string& as) {
  for (const auto& c : spec.choices)
    if (c == value) return;
  throw UsageError(as + ": '" + value + "' is not " + accepted_text(spec));
}

}  // namespace lambert
