#pragma once
// Options shared by subcommands and the load-and-mesh step they all start with.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "apps/option_scope.hpp"
#include "geometry/bvh.hpp"
#include "geometry/formfactors/formfactors.hpp"
#include "geometry/mesh.hpp"
#include "geometry/scene.hpp"
#include "io/obj_loader.hpp"

namespace lambert {

struct Medium;

/// Scene file, how to load it and meshing target.
struct SceneArgs {
  std::string scene;                 ///< OBJ path; empty = built-in Cornell box
  LoadOptions load;  ///< --strict, --default-reflectance, --max-reflectance, --vertex-colors-as-reflectance
  bool default_reflectance_given = false;  ///< --default-reflectance was on the command line
  std::vector<std::string> emit;     ///< --emit NAME_OR_GLOB=R,G,B, parsed by load_scene
  double max_edge = 0.0;             ///< --max-edge
  std::int64_t patches = 0;          ///< --patches
  std::int64_t default_patches = 0;  ///< used when neither is given
  bool discontinuity = false;        ///< --discontinuity
  int discontinuity_sources = 0;     ///< --discontinuity-sources
};

/// Threads, seed and verbosity.
struct RunArgs {
  int threads = 0;          ///< -j; 0 = all cores
  std::uint64_t seed = 1;   ///< --seed
  bool quiet = false;       ///< -q
  bool verbose = false;     ///< -v
  std::string max_memory;   ///< --max-memory SIZE; empty = $LAMBERT_MAX_MEMORY or MemAvailable
  /// The subcommand these options belong to (set by add_run_options; it outlives the run),
  /// asked after parsing which options were given (apps/option_scope.hpp).
  const CLI::App* command = nullptr;
};

/// Adds the positional SCENE, the loading options (--strict, --default-reflectance,
/// --max-reflectance, --vertex-colors-as-reflectance, --emit), --max-edge / --patches and
/// --discontinuity / --discontinuity-sources to a subcommand.
void add_scene_options(CLI::App* cmd, SceneArgs& args);
/// Adds -j/--threads, --seed, -q/--quiet, -v/--verbose and --max-memory to a subcommand.
void add_run_options(CLI::App* cmd, RunArgs& args);
/// Refuses (UsageError) an option given on the command line of `args.command` that the
/// choices in `selection` do not read (apps/option_scope.hpp).
void check_options_read(const RunArgs& args, const Selection& selection);
/// Applies --quiet / --verbose to the logger.
void apply_run_options(const RunArgs& args);

/// A loaded and meshed scene.
struct LoadedScene {
  Scene scene;
  PatchMesh mesh;
  double max_edge = 0.0;  ///< the --max-edge actually used (0 = one element per face)
  bool discontinuity = false;  ///< meshed with --discontinuity (edges on the shadow lines)
  /// The mesh's BVH, built on first use by scene_bvh and shared by every stage of a run.
  mutable std::shared_ptr<const Bvh> bvh;
};

/// The BVH of the scene's mesh (built once, with `threads` Embree threads; 0 = all cores).
const Bvh& scene_bvh(const LoadedScene& scene, int threads);

/// CLI11 check for an output file option: its directory must exist (checked before any
/// work, so a long computation never ends in a failed write).
CLI::Validator output_file_check();

/// CLI11 check for an output prefix option (see output_prefix): a name ending in '/' is a
/// directory to create; otherwise the prefix's directory must exist.
CLI::Validator output_prefix_check();

/// Where a command writing several files puts them: for -o DIR (an existing directory, or
/// a name ending in '/', created if needed) the prefix DIR/<name>; otherwise -o is the prefix.
std::string output_prefix(const std::string& output, const std::string& name);

/// CLI11 check for a floating-point option: a finite number (NaN and inf refused) in
/// [lo, hi], open at lo when `open_low` and at hi when `open_high`; hi = infinity means no
/// upper bound. The message states the range.
CLI::Validator finite_number(double lo, double hi, bool open_low = false, bool open_high = false);

/// CLI11 check for a floating-point value that may be any finite number (NaN, inf refused).
CLI::Validator any_finite_number();

/// A file a command reads or writes, with the option that names it (for messages).
struct NamedFile {
  std::string option;  ///< e.g. "--ff", "-o", "the scene"
  std::string path;
};

/// What a command will read, write and hold in memory, checked by load_scene after loading
/// the scene and before meshing it (so before any work that takes time).
struct JobPlan {
  std::vector<NamedFile> inputs;   ///< besides the scene's own files (Scene::files)
  std::vector<NamedFile> outputs;  ///< every file the command may write
  std::optional<FormFactorOptions> ff;  ///< F that will be computed here (none: loaded or unused)
  std::string max_memory;          ///< RunArgs::max_memory
  bool direct = false;  ///< the job solves with `direct`: its factorisation is counted (for a
                        ///< computed F, at the all-pairs bound: a dense LU of N patches)
  const Medium* medium = nullptr;  ///< a participating medium whose zones join F here
  int medium_rays = 0;             ///< its rays per unknown (--medium-rays)
};

/// The memory a job may use, and where that limit comes from ("--max-memory 512M",
/// "LAMBERT_MAX_MEMORY 1G" or "MemAvailable").
struct MemoryLimit {
  double bytes = 0.0;
  std::string source;
};

/// The job's limit: --max-memory (`max_memory`), else $LAMBERT_MAX_MEMORY, else MemAvailable;
/// nullopt for "0" or where none is known. Throws UsageError for a malformed size.
std::optional<MemoryLimit> job_memory_limit(const std::string& max_memory);

/// A plan with the run's --max-memory and nothing else.
JobPlan job_plan(const RunArgs& run);

/// Refuses (UsageError) an output that is an input or another output (paths compared after
/// std::filesystem::weakly_canonical, so ./a/../s.obj is s.obj), then checks that every
/// output directory accepts a new file by creating and removing a probe file (IoError).
void check_job_files(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs);

/// Refuses (UsageError) a job whose estimated peak memory (mesh_peak_bytes, and
/// form_factor_peak_bytes for plan.ff, and direct_memory_bytes at the all-pairs bound for
/// plan.direct with plan.ff) exceeds the limit: --max-memory, else $LAMBERT_MAX_MEMORY, else
/// MemAvailable (no check where none is known; "0" = no check). When direct's factorisation
/// alone is above the limit, the message is direct_refusal's.
void check_job_memory(std::int64_t patches, const JobPlan& plan);

/// The meshing options of the scene arguments (--max-edge, --patches or the default target,
/// --discontinuity, --discontinuity-sources).
MeshOptions mesh_options(const SceneArgs& args);

/// Loads the scene (or the built-in Cornell box) with the loading options.
Scene load_scene_file(const SceneArgs& args);
/// Loads the scene (or the built-in Cornell box) and checks the plan's files against the
/// scene's (check_job_files), without meshing it (a method that meshes on its own).
Scene load_checked_scene(const SceneArgs& args, const JobPlan& plan = {});
/// Loads the scene (or the built-in Cornell box), checks the plan's files against the
/// scene's and its memory estimate (check_job_files, check_job_memory), and meshes it.
LoadedScene load_scene(const SceneArgs& args, const JobPlan& plan = {});

}  // namespace lambert
