#include "pipeline/option_scope.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "pipeline/option_specs.hpp"

namespace lambert {

namespace {

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

std::vector<std::string> unread_options(const OptionGiven& given, const Selection& selection) {
  std::vector<std::string> out;
  if (!given) return out;
  // The rows of the command's options that some choices do not read, once per name (the
  // command's own row where it has one). formfactors' --ff-tol is also --tol there: `given`
  // answers for first long names only, so its row is --ff-tol's.
  std::vector<std::string> seen;
  for (const OptionSpec& s : option_specs()) {
    if (!s.reads || std::find(seen.begin(), seen.end(), s.name) != seen.end()) continue;
    seen.push_back(s.name);
    const OptionSpec* row = find_option_spec(s.name, selection.command);
    if (row && row->reads && given(row->name) && !row->reads(selection)) out.push_back(row->name);
  }
  return out;
}

void check_option_scopes(const OptionGiven& given, const Selection& selection) {
  const std::vector<std::string> unread = unread_options(given, selection);
  if (unread.empty()) return;
  const OptionSpec& row = option_spec(unread.front(), selection.command);
  throw UsageError(row.name + " does not apply to " + describe(selection) + " (read by " +
                   row.reader + ")");
}

}  // namespace lambert
