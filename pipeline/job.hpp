#pragma once
// A job's settings that every command shares (the scene and how to mesh it; threads, seed,
// verbosity, memory limit) and the load-and-mesh step they all start with, with the checks
// of files and memory made before any work. No CLI here: apps/options.hpp registers them.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/scene.hpp"
#include "geometry/visibility/bvh.hpp"
#include "io/obj_loader.hpp"
#include "pipeline/option_scope.hpp"

namespace lambert {

struct Medium;

/// Reads a whole string as a finite number (false for NaN, inf and trailing text).
bool parse_finite_number(const std::string& text, double& x);

/// Reads "R,G,B": three finite numbers >= 0, and <= 1 for a reflectance (`unit`). Returns the
/// reason it is not one, empty on success.
std::string parse_rgb(const std::string& text, bool unit, Eigen::Vector3d& out);

/// Reads --emit NAME_OR_GLOB=R,G,B (the last '=' separates: names may hold one). Returns the
/// reason it is not one, empty on success.
std::string parse_emit(const std::string& text, EmitRule& rule);
/// Parses --sun DX,DY,DZ,R,G,B into `light` (its direction normalised); returns the reason
/// it is not one ("" when it is): six finite numbers, a direction of non-zero length, an
/// irradiance R,G,B >= 0.
std::string parse_sun(const std::string& text, Daylight& light);

/// Scene file, how to load it and meshing target.
struct SceneArgs {
  std::string scene;  ///< OBJ path; empty = built-in Cornell box
  /// --strict, --default-reflectance, --max-reflectance, --vertex-colors-as-reflectance,
  /// --split-angle
  LoadOptions load;
  bool default_reflectance_given = false;    ///< --default-reflectance was on the command line
  std::vector<std::string> emit;             ///< --emit NAME_OR_GLOB=R,G,B, parsed by load_scene
  double max_edge = 0.0;                     ///< --max-edge
  std::int64_t patches = 0;                  ///< --patches
  std::int64_t default_patches = 0;          ///< used when neither is given
  int surface_floor = kDefaultSurfaceFloor;  ///< --surface-floor
  bool discontinuity = false;                ///< --discontinuity
  int discontinuity_sources = 0;             ///< --discontinuity-sources
  /// The command computes B from the emission: a scene where nothing emits (and no
  /// participating medium of the job's plan emits) is refused when loaded, before any work
  /// (UsageError naming --emit), instead of a long run that ends in a black result.
  bool require_emitter = false;
  std::vector<double> sky;  ///< --sky R,G,B (radiance); empty = no sky
  std::string sun;          ///< --sun DX,DY,DZ,R,G,B; empty = no sun
};

/// Threads, seed and verbosity.
struct RunArgs {
  int threads = 0;         ///< -j; 0 = all cores
  std::uint64_t seed = 1;  ///< --seed
  bool quiet = false;      ///< -q
  bool verbose = false;    ///< -v
  std::string max_memory;  ///< --max-memory SIZE; empty = $LAMBERT_MAX_MEMORY or MemAvailable
  /// Which options the front end was given (the CLI sets it; empty = none).
  OptionGiven given;
};

/// Refuses (UsageError) an option given (`args.given`) that the choices in `selection` do not
/// read (pipeline/option_scope.hpp).
void check_options_read(const RunArgs& args, const Selection& selection);
/// Applies --quiet / --verbose to the logger.
void apply_run_options(const RunArgs& args);

/// A loaded and meshed scene.
struct LoadedScene {
  Scene scene;
  PatchMesh mesh;
  double max_edge = 0.0;       ///< the --max-edge actually used (0 = one element per face)
  bool discontinuity = false;  ///< meshed with --discontinuity (edges on the shadow lines)
  bool adapted = false;        ///< refined by --adapt / --adapt-patches (a graded mesh)
  /// The mesh's BVH, built on first use by scene_bvh and shared by every stage of a run.
  mutable std::shared_ptr<const Bvh> bvh;
  /// The patches' mean sun irradiance, computed on first use by sun_patch_part
  /// (daylight_stage.hpp) for the solve and reused by the render; `sun_part_key` names the
  /// mesh and seed it belongs to (recomputed when either changes, as adaptive meshing does).
  mutable std::shared_ptr<const Eigen::MatrixX3d> sun_part;
  mutable std::uint64_t sun_part_key = 0;
};

/// The BVH of the scene's mesh (built once, with `threads` Embree threads; 0 = all cores).
const Bvh& scene_bvh(const LoadedScene& scene, int threads);

/// Where a command writing several files puts them, and the folder it creates for them.
struct OutputPrefix {
  std::string prefix;  ///< DIR/<name> for -o DIR, else -o itself
  std::string folder;  ///< DIR when it does not exist yet (JobPlan::folders), else empty
};
/// The prefix of -o `output`: for DIR (an existing directory, or a name ending in '/') the
/// prefix DIR/<name>; otherwise -o is the prefix. Creates nothing.
OutputPrefix plan_output_prefix(const std::string& output, const std::string& name);
/// plan_output_prefix's prefix, with its folder created now (IoError if it cannot be).
std::string output_prefix(const std::string& output, const std::string& name);

/// The JSON summary written beside a table -o FILE: FILE.csv gives FILE.json, another name
/// FILE gives FILE.json; empty for a device or pipe (writes_in_place: nothing beside it).
std::string summary_beside(const std::string& file);

/// A file a command reads or writes, with the option that names it (for messages).
struct NamedFile {
  std::string option;  ///< e.g. "--ff", "-o", "the scene"
  std::string path;
};

/// What a command will read, write and hold in memory, checked by load_scene after loading
/// the scene and before meshing it (so before any work that takes time).
struct JobPlan {
  std::vector<NamedFile> inputs;        ///< besides the scene's own files (Scene::files)
  std::vector<NamedFile> outputs;       ///< every file the command may write
  /// Folders the job creates (-o DIR/): outputs may go into them; load_scene creates them
  /// once the files are checked.
  std::vector<std::string> folders;
  std::optional<FormFactorOptions> ff;  ///< F that will be computed here (none: loaded or unused)
  std::string max_memory;               ///< RunArgs::max_memory
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
/// std::filesystem::weakly_canonical, so ./a/../s.obj is s.obj; a device or pipe may take
/// several), or whose directory neither exists nor is in (or under) `folders`, the folders
/// the job will create; then checks that every output directory (for one to be created, its
/// nearest existing ancestor) accepts a new file by creating and removing a probe file, and
/// that a device or pipe is writable (IoError).
void check_job_files(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs,
                     const std::vector<std::string>& folders = {});

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
