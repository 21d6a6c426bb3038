#include "apps/common.hpp"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/obj_loader.hpp"

namespace lambert {
namespace {

// A whole string as a finite number (false for NaN, inf, trailing text).
bool parse_finite_number(const std::string& text, double& x) {
  std::size_t used = 0;
  try {
    x = std::stod(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used == text.size() && std::isfinite(x);
}

// Reads "R,G,B": three finite numbers >= 0, and <= 1 for a reflectance (`unit`); returns
// a reason, empty on success.
std::string parse_rgb(const std::string& text, bool unit, Eigen::Vector3d& out) {
  const std::string want = unit ? "R,G,B with three numbers in [0, 1]" : "R,G,B with three finite numbers >= 0";
  std::istringstream in(text);
  std::string part;
  int n = 0;
  while (std::getline(in, part, ',')) {
    double x = 0;
    if (n == 3 || !parse_finite_number(part, x) || x < 0 || (unit && x > 1))
      return "'" + text + "' is not " + want;
    out[n++] = x;
  }
  return n == 3 ? "" : "'" + text + "' is not " + want;
}

// --emit NAME_OR_GLOB=R,G,B (the last '=' separates: names may hold one).
std::string parse_emit(const std::string& text, EmitRule& rule) {
  const auto eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0) return "--emit '" + text + "': expected NAME_OR_GLOB=R,G,B";
  rule.pattern = text.substr(0, eq);
  const std::string why = parse_rgb(text.substr(eq + 1), false, rule.emission);
  return why;
}

}  // namespace

void add_scene_options(CLI::App* cmd, SceneArgs& args) {
  cmd->add_option("scene", args.scene, "OBJ scene file (default: the built-in Cornell box)");
  cmd->add_flag("--strict", args.load.strict,
                "Refuse missing or undefined materials and Kd = 1 instead of defaulting with a warning");
  cmd->add_option_function<std::string>(
         "--default-reflectance",
         [&args](const std::string& s) { parse_rgb(s, true, args.load.default_reflectance); },
         "Reflectance R,G,B of the default material (default 0.5,0.5,0.5)")
      ->check([](const std::string& s) {
        Eigen::Vector3d c;
        return parse_rgb(s, true, c);
      });
  cmd->add_option("--max-reflectance", args.load.max_reflectance,
                  "Clamp every Kd channel above R to R (0 < R <= 1), with a warning")
      ->check([](const std::string& s) {
        double r = 0;
        return parse_finite_number(s, r) && r > 0 && r <= 1 ? std::string()
                                                            : "'" + s + "' is not a number in (0, 1]";
      });
  cmd->add_flag("--vertex-colors-as-reflectance", args.load.vertex_colors_as_reflectance,
                "Each face whose corners all have colours (v x y z r g b) reflects their mean "
                "instead of its material's Kd");
  cmd->add_option("--emit", args.emit,
                  "NAME_OR_GLOB=R,G,B: surfaces (or materials) matching the name or glob emit "
                  "radiosity R,G,B (repeatable; later rules win)")
      ->check([](const std::string& s) {
        EmitRule r;
        return parse_emit(s, r);
      });
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

Scene load_scene_file(const SceneArgs& args) {
  LoadOptions options = args.load;
  for (const auto& text : args.emit) {
    EmitRule rule;
    const std::string why = parse_emit(text, rule);
    if (!why.empty()) throw UsageError("--emit: " + why);
    options.emit.push_back(rule);
  }
  return load_obj(args.scene.empty() ? builtin_cornell_box_path() : args.scene, nullptr, options);
}

LoadedScene load_scene(const SceneArgs& args) {
  LoadedScene out;
  out.scene = load_scene_file(args);
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
