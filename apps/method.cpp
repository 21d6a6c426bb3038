#include "apps/method.hpp"

#include <algorithm>
#include <limits>

#include "apps/medium_stage.hpp"
#include "core/error.hpp"

namespace lambert {

namespace {
std::vector<Method> base_methods() {
  return {
      {"matrix",
       "mesh the scene, compute F, solve (I - rho F) B = E",
       {"--patches", "--max-edge", "--discontinuity", "--discontinuity-sources", "--adapt",
        "--adapt-patches", "--estimator", "--samples", "--rays", "--threshold", "--hemicube-res",
        "--reciprocity", "--symmetrize", "--ff"},
       {"--solver", "--solvers", "--omega", "--preconditioner", "--restart", "--ambient",
        "--radiosity"},
       "matrix meshes with --patches or --max-edge and computes F"},
      {"hierarchical",
       "hierarchical radiosity with clustering: adaptive links, no F",
       {"--epsilon", "--min-area", "--link-rays"},
       {},
       "hierarchical meshes adaptively and computes no F: it takes --epsilon, --min-area "
       "(the smallest element), --link-rays, --tol and --max-iter"},
  };
}

// methods() with the medium's options added to the matrix row (the medium is one of its
// problem options: apps/medium_stage.hpp owns the list).
std::vector<Method> with_medium_options() {
  std::vector<Method> out = base_methods();
  for (Method& m : out)
    if (m.name == "matrix")
      m.problem_options.insert(m.problem_options.end(), medium_option_names().begin(),
                               medium_option_names().end());
  return out;
}
}  // namespace

const std::vector<Method>& methods() {
  static const std::vector<Method> kMethods = with_medium_options();
  return kMethods;
}

std::vector<std::string> method_names() {
  std::vector<std::string> names;
  for (const Method& m : methods()) names.push_back(m.name);
  return names;
}

const Method& find_method(const std::string& name) {
  for (const Method& m : methods())
    if (m.name == name) return m;
  throw UsageError("--method: unknown method '" + name + "'");
}

void add_method_options(CLI::App* cmd, MethodArgs& args, bool epsilon_list) {
  args.command = cmd;
  cmd->add_option("--method", args.name,
                  "How B is computed: matrix (F + solver) or hierarchical (adaptive links with "
                  "clustering, no F)")
      ->check(CLI::IsMember(method_names()))
      ->capture_default_str();
  // (0, 1): epsilon is a fraction of the emitted power; at 1 no link would ever refine.
  const CLI::Validator epsilon_range = finite_number(0.0, 1.0, true, true);
  const std::string epsilon_help =
      "hierarchical: refine a link while its power error exceeds EPSILON x the emitted power";
  if (epsilon_list)
    cmd->add_option("--epsilon", args.hierarchical.epsilons,
                    epsilon_help + " (comma-separated: one hierarchical run each)")
        ->delimiter(',')
        ->check(epsilon_range)
        ->capture_default_str();
  else
    cmd->add_option("--epsilon", args.hierarchical.epsilon, epsilon_help)
        ->check(epsilon_range)
        ->capture_default_str();
  cmd->add_option("--min-area", args.hierarchical.min_area,
                  "hierarchical: smallest element area, scene units^2 (0 = total area x 1e-5)")
      ->check(finite_number(0.0, std::numeric_limits<double>::infinity()))
      ->capture_default_str();
  cmd->add_option("--link-rays", args.hierarchical.link_rays,
                  "hierarchical: visibility rays per element link (samples per cluster link)")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
}

bool option_given(const MethodArgs& args, const std::string& option) {
  if (args.command == nullptr) return false;
  const CLI::Option* o = args.command->get_option_no_throw(option);
  return o != nullptr && o->count() > 0;
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
