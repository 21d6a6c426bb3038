#pragma once
// The solver settings' memory limit and the report pieces of a solve (energy balance,
// surface averages, CSV fields), shared by every command that solves.

#include <string>

#include "io/json.hpp"
#include "pipeline/problem.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// Sets options.memory_limit / memory_limit_source from the job's limit (job_memory_limit of
/// --max-memory), so that `direct` refuses a factorisation above it.
void set_memory_limit(SolveOptions& options, const std::string& max_memory);

/// "R", "G" or "B".
const char* channel_name(int channel);

/// An energy balance as a JSON object {emitted, absorbed, escaped, relative_imbalance,
/// residual_part, non_reciprocity_part (W, signed), relative_residual_part,
/// relative_non_reciprocity_part (the parts over emitted)}.
Json energy_json(const EnergyBalance& e);

/// Per-surface averages as a JSON array of {name, area, patches, average_radiosity [R, G, B]}.
Json surface_averages_json(const std::vector<SurfaceRadiosity>& surfaces);

/// "residual part R, non-reciprocity part N": the imbalance's two parts relative to emitted.
std::string energy_split_text(const EnergyBalance& e);

/// Quotes a CSV field when it holds a comma, quote or newline (RFC 4180).
std::string csv_field(const std::string& s);

/// Formats a double for CSV/tables with full precision (%.17g).
std::string csv_number(double v);

}  // namespace lambert
