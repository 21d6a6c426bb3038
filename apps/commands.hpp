#pragma once
// One options struct, one registration function and one run function per subcommand.

#include <CLI/CLI.hpp>

#include "apps/distributed.hpp"
#include "apps/heat_outputs.hpp"
#include "apps/options.hpp"
#include "pipeline/adapt_stage.hpp"
#include "pipeline/ff_stage.hpp"
#include "pipeline/job.hpp"
#include "pipeline/medium_stage.hpp"
#include "pipeline/method.hpp"
#include "pipeline/render_stages.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// Options of `lambert info`.
struct InfoOptions {
  SceneArgs scene;
  RunArgs run;
  bool list_surfaces = false;  ///< --list-surfaces: names only, no meshing
};
/// Registers `info` on the app.
CLI::App* add_info_command(CLI::App& app, InfoOptions& opts);
/// Prints surfaces, materials, emitters, area, bounds and patch statistics.
int run_info(const InfoOptions& opts);

/// Options of `lambert formfactors`.
struct FormFactorsOptions {
  SceneArgs scene;
  RunArgs run;
  FormFactorArgs ff;
  std::string output;  ///< .mtx = Matrix Market, otherwise binary; JSON for --by-surface/--point
  std::string report;  ///< diagnostics JSON
  bool with_stderr = false;
  bool by_surface = false;
  std::vector<double> point, normal;  ///< sensor point and normal (3 each) or empty
  std::string precision = "double";   ///< --ff-precision: "double" or "float" (saved values)
  MediumArgs medium;  ///< participating medium: F then holds its zones after the patches
  DistributedArgs dist;               ///< --distributed
};
/// Registers `formfactors` on the app.
CLI::App* add_formfactors_command(CLI::App& app, FormFactorsOptions& opts);
/// Computes F and writes it (or surface / sensor-point view factors) plus diagnostics.
int run_formfactors(const FormFactorsOptions& opts);

/// Options of `lambert solve`.
struct SolveCommandOptions {
  SceneArgs scene;
  RunArgs run;
  MethodArgs method;
  FormFactorArgs ff;
  SolveOptions solve;
  AdaptArgs adapt;
  MediumArgs medium;                     ///< participating medium (matrix method)
  std::string output = "radiosity.csv";  ///< per-patch CSV; summary JSON beside it
  DistributedArgs dist;                  ///< --distributed, --petsc-options
};
/// Registers `solve` on the app.
CLI::App* add_solve_command(CLI::App& app, SolveCommandOptions& opts);
/// Solves K B = E with one solver; writes the CSV and JSON summary; 3 if not converged.
int run_solve(const SolveCommandOptions& opts);

/// Options of `lambert compare`.
struct CompareOptions {
  SceneArgs scene;
  RunArgs run;
  MethodArgs method;  ///< hierarchical: its runs (one per --epsilon) against a matrix reference
  FormFactorArgs ff;
  SolveOptions solve;                ///< tolerance etc. shared by every solver
  std::vector<std::string> solvers;  ///< empty = all
  std::string output = "compare";    ///< directory or file prefix
  MediumArgs medium;                 ///< participating medium (matrix method: zones join F)
};
/// Registers `compare` on the app.
CLI::App* add_compare_command(CLI::App& app, CompareOptions& opts);
/// Matrix: runs every solver on one system; prints and writes the table, histories and plots.
/// Hierarchical: one hierarchical run per --epsilon against the matrix reference (F + direct);
/// prints and writes the table and the per-surface averages.
int run_compare(const CompareOptions& opts);

/// Options of `lambert solvers`.
struct SolversOptions {
  RunArgs run;
};
/// Registers `solvers` on the app.
CLI::App* add_solvers_command(CLI::App& app, SolversOptions& opts);
/// Lists the solver names and descriptions.
int run_solvers(const SolversOptions& opts);

/// Options of `lambert options`.
struct OptionsOptions {
  bool markdown = false;          ///< --markdown: the reference table of docs/options.md
  const CLI::App* app = nullptr;  ///< the whole CLI, whose commands it lists
};
/// Registers `options` on the app.
CLI::App* add_options_command(CLI::App& app, OptionsOptions& opts);
/// Prints every option of every command: commands, accepted values, default, which choice
/// reads it, description (pipeline/option_specs.hpp and option_scope.hpp, and the CLI).
int run_options(const OptionsOptions& opts);

/// Options of `lambert render`.
struct RenderOptions {
  SceneArgs scene;
  RunArgs run;
  MethodArgs method;
  FormFactorArgs ff;
  SolveOptions solver;
  AdaptArgs adapt;
  CameraArgs camera;
  ShadeArgs shade;
  MediumArgs medium;                    ///< participating medium (matrix method, F + solve here)
  std::string radiosity;                ///< per-patch CSV from `solve`; empty = F + solve here
  std::string output = "render.exr";    ///< linear HDR image
  std::string png;                      ///< sRGB preview; empty = output with .png
  std::string vertex_exr;               ///< per-vertex radiosity EXR (optional)
  std::string ply;                      ///< coloured patch mesh (optional)
  std::string glb;  ///< glTF of the solution and its viewer page beside it (optional)
};
/// Registers `render` on the app.
CLI::App* add_render_command(CLI::App& app, RenderOptions& opts);
/// Renders B (from --radiosity or computed) to EXR + PNG, optionally vertex EXR and PLY.
int run_render(const RenderOptions& opts);

/// Options of `lambert run`.
struct RunOptions {
  SceneArgs scene;
  RunArgs run;
  MethodArgs method;
  FormFactorArgs ff;
  SolveOptions solver;
  AdaptArgs adapt;
  CameraArgs camera;
  ShadeArgs shade;
  MediumArgs medium;               ///< participating medium (matrix method)
  std::string output_dir = "out";  ///< -o: output directory, created if needed
  std::string name;                ///< file prefix; empty = scene stem ("cornell" built-in)
  DistributedArgs dist;            ///< --distributed, --petsc-options
};
/// Registers `run` on the app.
CLI::App* add_run_command(CLI::App& app, RunOptions& opts);
/// The whole pipeline with per-stage progress, a summary on stdout and every output file.
int run_run(const RunOptions& opts);

/// Options of `lambert accuracy`.
struct AccuracyOptions {
  SceneArgs scene;
  RunArgs run;
  std::string analytic_case;  ///< --case: a built-in analytic case instead of SCENE
  std::vector<std::string> estimators;  ///< families to run; empty = mc, hybrid, hemicube (gather on request)
  std::vector<int> mc_samples{4, 16, 64};
  std::vector<int> hybrid_samples{4, 16, 64};
  std::vector<int> gather_rays{256, 1024, 4096};  ///< --estimators gather
  std::vector<int> hemicube_res{32, 64, 128, 256};
  bool symmetrize = false;       ///< also run each hemicube resolution symmetrized
  int reference_samples = 1024;  ///< hybrid reference for scenes without a closed form
  std::string output = "accuracy";  ///< directory or file prefix
  MediumArgs medium;  ///< participating medium: every F (and the reference) gets its zones
};
/// Registers `accuracy` on the app.
CLI::App* add_accuracy_command(CLI::App& app, AccuracyOptions& opts);
/// Runs the estimators, compares F and B with the reference; table, CSVs and plot.
int run_accuracy(const AccuracyOptions& opts);

/// Options of `lambert heat`.
struct HeatOptions {
  SceneArgs scene;
  RunArgs run;
  FormFactorArgs ff;
  SolveOptions solve;
  std::string surfaces;              ///< --surfaces FILE.json (io/heat_surfaces.hpp)
  double ambient_temperature = 0.0;  ///< --ambient-temperature (K)
  std::string length_unit = "m";     ///< --length-unit: m, cm, mm or in
  std::string output = "heat";       ///< -o: FILE.csv, or prefix (or DIR/) of the CSVs and JSON
  std::string patches_csv;           ///< --patches-csv FILE (default: PREFIX_patches.csv)
  std::string conductors;            ///< --conductors FILE.csv: the radiative conductors
  HeatImageArgs images;              ///< --vertex-exr, --ply, --image and the camera
};
/// Registers `heat` on the app.
CLI::App* add_heat_command(CLI::App& app, HeatOptions& opts);
/// Gray-diffuse radiative exchange: T, J, q, Q per patch and surface; 3 if not converged.
int run_heat(const HeatOptions& opts);

}  // namespace lambert
