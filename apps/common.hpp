#pragma once
// Options shared by subcommands and the load-and-mesh step they all start with.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <memory>
#include <string>

#include "geometry/bvh.hpp"
#include "geometry/mesh.hpp"
#include "geometry/scene.hpp"
#include "io/obj_loader.hpp"

namespace lambert {

/// Scene file, how to load it and meshing target.
struct SceneArgs {
  std::string scene;                 ///< OBJ path; empty = built-in Cornell box
  LoadOptions load;  ///< --strict, --default-reflectance, --max-reflectance, --vertex-colors-as-reflectance
  std::vector<std::string> emit;     ///< --emit NAME_OR_GLOB=R,G,B, parsed by load_scene
  double max_edge = 0.0;             ///< --max-edge
  std::int64_t patches = 0;          ///< --patches
  std::int64_t default_patches = 0;  ///< used when neither is given
};

/// Threads, seed and verbosity.
struct RunArgs {
  int threads = 0;          ///< -j; 0 = all cores
  std::uint64_t seed = 1;   ///< --seed
  bool quiet = false;       ///< -q
  bool verbose = false;     ///< -v
};

/// Adds the positional SCENE, the loading options (--strict, --default-reflectance,
/// --max-reflectance, --vertex-colors-as-reflectance, --emit) and --max-edge / --patches to
/// a subcommand.
void add_scene_options(CLI::App* cmd, SceneArgs& args);
/// Adds -j/--threads, --seed, -q/--quiet and -v/--verbose to a subcommand.
void add_run_options(CLI::App* cmd, RunArgs& args);
/// Applies --quiet / --verbose to the logger.
void apply_run_options(const RunArgs& args);

/// A loaded and meshed scene.
struct LoadedScene {
  Scene scene;
  PatchMesh mesh;
  double max_edge = 0.0;  ///< the --max-edge actually used (0 = one element per face)
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

/// Loads the scene (or the built-in Cornell box) with the loading options.
Scene load_scene_file(const SceneArgs& args);
/// Loads the scene (or the built-in Cornell box) and meshes it.
LoadedScene load_scene(const SceneArgs& args);

}  // namespace lambert
