#pragma once
// Adaptive meshing for `solve` and `run` (--method matrix): solve, estimate each patch's
// error, bisect the worst patches conformingly, update only the form factors of the
// changed patches, re-solve from the previous solution, repeat (geometry/mesh/adapt.hpp).

#include <cstdint>
#include <vector>

#include "io/json.hpp"
#include "pipeline/ff_stage.hpp"
#include "pipeline/job.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// --adapt ROUNDS, --adapt-patches N.
struct AdaptArgs {
  int rounds = 0;            ///< --adapt: refinement rounds (0 = none unless a budget)
  std::int64_t patches = 0;  ///< --adapt-patches: stop once the mesh has this many patches
  bool active() const { return rounds > 0 || patches > 0; }
};

/// Marked per round: this fraction of the patches, the largest error estimates first.
constexpr double kAdaptFraction = 0.2;
/// Rounds at most when only a patch budget is given.
constexpr int kAdaptMaxRounds = 30;

/// One round's report: the mesh solved in it, its estimated error, and its cost.
struct AdaptRound {
  int round = 0;  ///< 0 = the initial mesh
  std::int64_t patches = 0;
  std::int64_t changed = 0;      ///< patches whose form factors were (re)computed
  double estimated_error = 0.0;  ///< Σ patch_errors / Σ A (W/m², mean over the area)
  double seconds = 0.0;          ///< form factors + solve of this round
  double solve_seconds = 0.0;    ///< the solve alone
  std::int64_t rays = 0;
};

/// The adaptive loop on a loaded scene (its mesh is replaced by the refined one, its quads
/// split into triangles first). `ff` and `solution` receive the final F and B. Throws
/// UsageError with --ff (adaptation computes F). Logs one line per round on stderr.
std::vector<AdaptRound> adapt_scene(LoadedScene& scene, const FormFactorArgs& ff_args,
                                    const SolveOptions& solver, const RunArgs& run,
                                    const AdaptArgs& adapt, FormFactors& ff,
                                    RadiositySolution& solution);

/// The rounds as JSON: [{round, patches, changed, estimated_error, seconds, rays}].
Json adapt_json(const std::vector<AdaptRound>& rounds);

}  // namespace lambert
