#include "apps/common.hpp"

#include <filesystem>

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/obj_loader.hpp"

namespace lambert {

void add_scene_options(CLI::App* cmd, SceneArgs& args) {
  cmd->add_option("scene", args.scene, "OBJ scene file (default: the built-in Cornell box)");
  auto* edge = cmd->add_option("--max-edge", args.max_edge, "Longest patch edge, in scene units")
                   ->check(CLI::PositiveNumber);
  cmd->add_option("--patches", args.patches, "Approximate total number of patches")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{100000000}))
      ->excludes(edge);
}

void add_run_options(CLI::App* cmd, RunArgs& args) {
  cmd->add_option("-j,--threads", args.threads, "Worker threads (default: all cores)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--seed", args.seed, "Random seed (results are bitwise reproducible)");
  cmd->add_flag("-q,--quiet", args.quiet, "No progress or log output on stderr");
  cmd->add_flag("-v,--verbose", args.verbose, "More log output on stderr");
}

void apply_run_options(const RunArgs& args) {
  set_log_level(args.quiet     ? LogLevel::Quiet
                : args.verbose ? LogLevel::Verbose
                               : LogLevel::Normal);
}

CLI::Validator output_file_check() {
  return CLI::Validator(
      [](std::string& path) -> std::string {
        namespace fs = std::filesystem;
        const fs::path dir = fs::path(path).parent_path();
        std::error_code ec;
        if (!dir.empty() && !fs::is_directory(dir, ec))
          return "cannot write '" + path + "': directory '" + dir.string() + "' does not exist";
        return "";
      },
      "FILE");
}

CLI::Validator output_prefix_check() {
  return CLI::Validator(
      [](std::string& out) -> std::string {
        if (!out.empty() && out.back() == '/') return "";  // created when writing
        return output_file_check()(out);
      },
      "DIR/|PREFIX");
}

std::string output_prefix(const std::string& output, const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!output.empty() && (output.back() == '/' || fs::is_directory(output, ec))) {
    fs::create_directories(output, ec);
    if (ec) throw IoError(output + ": cannot create directory: " + ec.message());
    return (fs::path(output) / name).string();
  }
  return output;
}

LoadedScene load_scene(const SceneArgs& args) {
  LoadedScene out;
  out.scene = load_obj(args.scene.empty() ? builtin_cornell_box_path() : args.scene);
  MeshOptions mo;
  mo.max_edge = args.max_edge;
  mo.target_patches = args.patches > 0 || args.max_edge > 0 ? args.patches : args.default_patches;
  out.mesh = mesh_scene(out.scene, mo);
  out.max_edge = out.mesh.max_edge;
  return out;
}

const Bvh& scene_bvh(const LoadedScene& scene, int threads) {
  if (!scene.bvh) scene.bvh = std::make_shared<const Bvh>(scene.mesh, threads);
  return *scene.bvh;
}

}  // namespace lambert
