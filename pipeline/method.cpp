#include "pipeline/method.hpp"

#include <algorithm>
#include <limits>

#include "core/error.hpp"
#include "pipeline/option_specs.hpp"

namespace lambert {

namespace {
// The registry; each method's options are the rows of pipeline/option_specs.cpp that name it.
std::vector<Method> base_methods() {
  return {
      {"matrix",
       "mesh the scene, compute F, solve (I - rho F) B = E",
       {},
       {},
       "matrix meshes with --patches or --max-edge and computes F"},
      {"hierarchical",
       "hierarchical radiosity with clustering: adaptive links, no F",
       {},
       {},
       "hierarchical meshes adaptively and computes no F: it takes --epsilon, --min-area "
       "(the smallest element), --link-rays, --tol and --max-iter"},
  };
}

std::vector<Method> with_options() {
  std::vector<Method> out = base_methods();
  for (Method& m : out)
    for (const OptionSpec& s : option_specs()) {
      if (s.method != m.name) continue;
      std::vector<std::string>& list = s.method_solver ? m.solver_options : m.problem_options;
      if (std::find(list.begin(), list.end(), s.name) == list.end()) list.push_back(s.name);
    }
  return out;
}
}  // namespace

const std::vector<Method>& methods() {
  static const std::vector<Method> kMethods = with_options();
  return kMethods;
}

std::vector<std::string> method_names() {
  std::vector<std::string> names;  // (not from methods(), which reads the option table)
  for (const Method& m : base_methods()) names.push_back(m.name);
  return names;
}

const Method& find_method(const std::string& name) {
  for (const Method& m : methods())
    if (m.name == name) return m;
  throw UsageError("--method: unknown method '" + name + "'");
}

bool option_given(const MethodArgs& args, const std::string& option) {
  return args.given && args.given(option);
}

void check_method_options(const MethodArgs& args, const std::string& reference) {
  const Method& chosen = find_method(args.name);
  const auto refuse = [&](const std::string& option, const Method& owner) {
    if (!option_given(args, option)) return;
    throw UsageError(option + " does not apply to --method " + chosen.name +
                     " (an option of --method " + owner.name + "; " + chosen.instead + ")");
  };
  for (const Method& m : methods()) {
    if (m.name == chosen.name) continue;
    if (m.name != reference)
      for (const std::string& o : m.problem_options) refuse(o, m);
    for (const std::string& o : m.solver_options) refuse(o, m);
  }
}

HierarchicalOptions make_hierarchical_options(const MethodArgs& args, double epsilon,
                                              const SolveOptions& solve, const RunArgs& run) {
  HierarchicalOptions o;
  o.epsilon = epsilon;
  o.min_area = args.hierarchical.min_area;
  o.link_rays = args.hierarchical.link_rays;
  if (option_given(args, "--tol")) o.tol = solve.tol;
  if (option_given(args, "--max-iter")) o.max_iterations = solve.max_iterations;
  o.seed = run.seed;
  o.threads = run.threads;
  o.progress = !run.quiet;
  const auto limit = job_memory_limit(run.max_memory);
  o.memory_limit = limit ? limit->bytes : 0.0;
  return o;
}

}  // namespace lambert
