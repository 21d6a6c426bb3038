#pragma once
// The output stages of formfactors and solve, shared by their single-process and
// distributed (apps/distributed.cpp: rank 0 alone) runs.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "apps/commands.hpp"
#include "io/json.hpp"
#include "pipeline/daylight_stage.hpp"

namespace lambert {

/// The diagnostics report's path: --report, else OUTPUT with .report.json.
std::string formfactors_report_path(const FormFactorsOptions& opts);

/// Prints F's diagnostics and writes F (binary, Matrix Market or the --by-surface table)
/// and the report, to which `distributed` (unless null) is added as "distributed". With a
/// `medium` the zones are appended to `ff` after the diagnostics (F then holds patches and
/// zones) and the report gains a "medium" section.
void write_formfactors_outputs(const FormFactorsOptions& opts, const LoadedScene& scene,
                               FormFactors& ff, const std::string& report,
                               const Json& distributed, const Medium* medium = nullptr);

/// What `solve --method matrix` computed, for its outputs.
struct MatrixSolveResult {
  SolveOptions options;  ///< solver settings (solver: the name reported)
  RadiositySolution solution;
  FormFactorOptions ff_options;  ///< the settings that made F
  double load_seconds = 0.0, ff_seconds = 0.0;
  std::int64_t nonzeros = 0;  ///< entries of F (of the extended F with a medium)
  std::optional<MediumResult> medium;
  std::vector<AdaptRound> rounds;
  Json distributed;  ///< the "distributed" section of the summary (null: none)
  DaylightSources daylight;  ///< what the sky and the sun brought (empty: none)
};

/// Writes the per-patch CSV and the JSON summary, prints the per-channel lines; returns
/// the exit code (kExitNotConverged with a warning when a channel did not converge).
int write_solve_outputs(const SolveCommandOptions& opts, const LoadedScene& loaded,
                        const MatrixSolveResult& result);

}  // namespace lambert
