#pragma once
// The files and the table `lambert heat` writes: per-surface and per-patch CSV, the VTU of
// per-patch results, the JSON summary, the per-vertex EXR and PLY (temperature, heat flux,
// radiosity) and the colour-mapped image with its legend.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "io/heat_surfaces.hpp"
#include "io/json.hpp"
#include "pipeline/job.hpp"
#include "pipeline/render_stages.hpp"
#include "solvers/gebhart.hpp"
#include "solvers/thermal.hpp"

namespace lambert {

struct HeatOptions;

/// The summary carries the conductor matrix up to this many surfaces (64² numbers, ~80 kB of
/// JSON); above it, only where the CSV is and the totals.
constexpr std::int32_t kJsonConductorSurfaces = 64;

/// --vertex-exr, --ply, --image, --image-quantity and the camera options of `heat`.
struct HeatImageArgs {
  std::string vertex_exr;                ///< channels temperature, heat_flux, radiosity
  std::string ply;                       ///< coloured by --image-quantity
  std::string image;                     ///< colour-mapped PNG with a legend
  std::string quantity = "temperature";  ///< temperature or flux
  std::string glb;                       ///< glTF of T, q and J, the viewer page beside it
  CameraArgs camera;
};
/// Adds the image and per-vertex output options to `heat`.
void add_heat_output_options(CLI::App* cmd, HeatImageArgs& args);
/// Refuses (UsageError) the picture options no picture reads: the camera options without
/// --image or --glb, --image-quantity without --image or --ply.
void check_heat_output_options(const HeatImageArgs& args, const OptionGiven& given);
/// Adds those outputs to the job plan (collision and folder checks).
void add_heat_outputs_to_plan(JobPlan& plan, const HeatImageArgs& args);

/// Where `heat` writes its tables and its summary (empty: not written).
struct HeatPaths {
  std::string surfaces_csv, patches_csv, json, conductors_csv;
  std::string vtu;     ///< -o FILE.vtu: per-patch cell data, per-surface field data
  std::string folder;  ///< the folder -o DIR/ creates (JobPlan::folders), empty if none
};
/// -o FILE.csv, or a device or pipe (/dev/null, /dev/stdout): the per-surface table goes to
/// it, the summary beside it (FILE.json; none for a device), the per-patch table only with
/// --patches-csv. -o FILE.vtu: the VTU (no per-surface CSV: the table is its field data), the
/// summary FILE.json, the per-patch table only with --patches-csv. -o PREFIX or DIR/ (compatible
/// with earlier versions): PREFIX_surfaces.csv, PREFIX_patches.csv (or --patches-csv) and
/// PREFIX.json. --conductors as given.
HeatPaths heat_paths(const HeatOptions& o);
/// Adds the paths to the plan as outputs, and the folder -o DIR/ creates.
void add_heat_paths_to_plan(JobPlan& plan, const HeatPaths& paths);

/// Seconds spent per stage.
struct HeatTimings {
  double load_seconds = 0.0, form_factors_seconds = 0.0, solve_seconds = 0.0, total_seconds = 0.0;
};

/// Everything a heat report reads (not owned).
struct HeatReport {
  const LoadedScene* loaded = nullptr;
  const ThermalProblem* problem = nullptr;
  const ThermalSolution* solution = nullptr;
  const std::vector<SurfaceHeat>* surfaces = nullptr;
  const std::vector<SurfaceCondition>* conditions = nullptr;  ///< per surface
  const FormFactors* ff = nullptr;
  const HeatOptions* options = nullptr;
  const RadiativeConductors* conductors = nullptr;  ///< computed for --conductors, else null
  HeatTimings timings;
};

/// surface,emissivity,condition,given,area_m2,patches,T_mean_K,T_min_K,T_max_K,J_W_m2,
/// q_W_m2,Q_W — one row per surface, then an `environment` row (Q only), atomically.
void write_heat_surfaces_csv(const std::string& path, const HeatReport& r);
/// patch,surface,area_m2,emissivity,T_K,J_W_m2,H_W_m2,q_W_m2,Q_W, atomically.
void write_heat_patches_csv(const std::string& path, const HeatReport& r);
/// The mesh with per-patch T_K, q_W_m2, Q_W, J_W_m2, H_W_m2, emissivity, area_m2 and surface
/// (index) as cell data and the per-surface table as field data (surface_names, then
/// surface_<column> of the per-surface CSV, environment_W, closure_W), atomically; undefined
/// temperatures are NaN.
void write_heat_vtu(const std::string& path, const HeatReport& r);
/// The conductors as a matrix: header `GR_m2,<surface>...,environment`, one row per emitting
/// surface (GR_ST in m², then GR_S,env), atomically.
void write_heat_conductors_csv(const std::string& path, const HeatReport& r);
/// The JSON summary: settings (scene, surfaces file, length unit, ambient, σ, form factors,
/// solver), status, closure, environment, per-surface results, the conductors when computed
/// (the matrix itself up to kJsonConductorSurfaces surfaces), timings.
Json heat_json(const HeatReport& r);
/// The per-surface table and the closure on stdout.
void print_heat_table(const HeatReport& r);
/// Writes --vertex-exr, --ply and --image when asked; returns the paths written.
std::vector<std::string> write_heat_images(const HeatReport& r);

}  // namespace lambert
