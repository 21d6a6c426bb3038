#include "pipeline/job.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/memory.hpp"
#include "geometry/formfactors/media.hpp"
#include "geometry/media/medium.hpp"
#include "io/obj_loader.hpp"
#include "io/stl_loader.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

bool parse_finite_number(const std::string& text, double& x) {
  std::size_t used = 0;
  try {
    x = std::stod(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used == text.size() && std::isfinite(x);
}

std::string parse_rgb(const std::string& text, bool unit, Eigen::Vector3d& out) {
  const std::string want =
      unit ? "R,G,B with three numbers in [0, 1]" : "R,G,B with three finite numbers >= 0";
  if (!text.empty() && text.back() == ',') return "'" + text + "' is not " + want;
  std::istringstream in(text);  // (getline drops an empty last field: checked above)
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

std::string parse_emit(const std::string& text, EmitRule& rule) {
  const auto eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0)
    return "--emit '" + text + "': expected NAME_OR_GLOB=R,G,B";
  rule.pattern = text.substr(0, eq);
  const std::string why = parse_rgb(text.substr(eq + 1), false, rule.emission);
  return why;
}

std::string parse_sun(const std::string& text, Daylight& light) {
  const std::string want = "DX,DY,DZ,R,G,B: a direction the sunlight travels and its irradiance";
  double v[6];
  int n = 0;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    double x = 0;
    if (n == 6 || !parse_finite_number(text.substr(start, comma - start), x))
      return "'" + text + "' is not " + want;
    v[n++] = x;
    start = comma + 1;
  }
  if (n != 6) return "'" + text + "' is not " + want;
  const Eigen::Vector3d d(v[0], v[1], v[2]);
  const double length = d.norm();
  if (!(length > 0.0) || !std::isfinite(length))
    return "'" + text + "': the direction DX,DY,DZ has no length";
  if (v[3] < 0 || v[4] < 0 || v[5] < 0) return "'" + text + "': the irradiance R,G,B must be >= 0";
  light.sun_direction = d / length;
  light.sun_irradiance = Eigen::Vector3d(v[3], v[4], v[5]);
  return "";
}

namespace {

// The path as compared for collisions: absolute, with "." and ".." and symbolic links of the
// existing part resolved.
std::string canonical_text(const std::string& path) {
  std::error_code ec;
  // absolute first: weakly_canonical leaves a relative path none of whose parts exists
  // relative ("out/a.csv" for a folder out/ still to be created).
  const std::filesystem::path p =
      std::filesystem::weakly_canonical(std::filesystem::absolute(path, ec), ec);
  return ec ? std::filesystem::absolute(path).lexically_normal().string() : p.string();
}

// Creates and removes a probe file in `dir`; returns the reason it cannot, empty when it can.
std::string probe_directory(const std::filesystem::path& dir) {
  const std::string probe = (dir / (".lambert-probe." + std::to_string(::getpid()))).string();
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (fd < 0) return std::strerror(errno);
  ::close(fd);
  std::remove(probe.c_str());
  return "";
}

}  // namespace

std::optional<MemoryLimit> job_memory_limit(const std::string& option) {
  std::string text = option, from = "--max-memory";
  if (text.empty()) {
    const char* env = std::getenv("LAMBERT_MAX_MEMORY");
    if (env != nullptr && *env != '\0') {
      text = env;
      from = "LAMBERT_MAX_MEMORY";
    }
  }
  if (text.empty()) {
    const auto available = available_memory_bytes();
    if (!available) return std::nullopt;
    return MemoryLimit{*available, "MemAvailable"};
  }
  const auto bytes = parse_size(text);
  if (!bytes) throw UsageError(from + ": '" + text + "' is not a size such as 512M or 8G");
  if (*bytes == 0) return std::nullopt;
  return MemoryLimit{*bytes, from + " " + text};
}

JobPlan job_plan(const RunArgs& run) {
  JobPlan plan;
  plan.max_memory = run.max_memory;
  return plan;
}

namespace {

// Refuses an output that is an input or another output (a device or pipe may take several).
void refuse_collisions(const std::vector<NamedFile>& inputs,
                       const std::vector<NamedFile>& outputs) {
  std::vector<std::pair<std::string, const NamedFile*>> seen;  // canonical path, its file
  for (const NamedFile& in : inputs)
    if (!in.path.empty()) seen.emplace_back(canonical_text(in.path), &in);
  const size_t n_inputs = seen.size();
  for (const NamedFile& out : outputs) {
    if (out.path.empty() || writes_in_place(out.path)) continue;
    const std::string key = canonical_text(out.path);
    for (size_t k = 0; k < seen.size(); ++k) {
      if (seen[k].first != key) continue;
      const NamedFile& other = *seen[k].second;
      throw UsageError(out.path + ": the output " + out.option + " would overwrite " +
                       (k < n_inputs ? "the input " : "the output ") + other.option + " '" +
                       other.path + "': choose another name");
    }
    seen.emplace_back(key, &out);
    std::error_code ec;
    if (std::filesystem::is_directory(out.path, ec))
      throw IoError(out.path + ": cannot write " + out.option + ": it is a folder");
  }
}

// The folder to probe for an output into `parent`: itself when it exists; for one the job
// creates (in or under `folders`), its nearest existing ancestor; empty when it is neither.
std::filesystem::path probe_target(const std::filesystem::path& parent,
                                   const std::vector<std::filesystem::path>& folders) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(parent, ec)) return parent;
  const bool planned = std::any_of(folders.begin(), folders.end(), [&](const fs::path& f) {
    const auto [end, rest] = std::mismatch(f.begin(), f.end(), parent.begin(), parent.end());
    return end == f.end();  // parent is f or lies under it
  });
  if (!planned) return {};
  fs::path p = parent;
  while (!p.empty() && p != p.parent_path() && !fs::exists(p, ec)) p = p.parent_path();
  return p;
}

}  // namespace

void check_job_files(const std::vector<NamedFile>& inputs, const std::vector<NamedFile>& outputs,
                     const std::vector<std::string>& folders) {
  namespace fs = std::filesystem;
  refuse_collisions(inputs, outputs);
  std::vector<fs::path> planned;
  for (const auto& f : folders) {
    const fs::path p = fs::path(canonical_text(f)).lexically_normal();
    planned.push_back(p.has_filename() ? p : p.parent_path());  // "out/" is "out"
  }
  std::vector<fs::path> probed;
  for (const NamedFile& out : outputs) {
    if (out.path.empty()) continue;
    if (writes_in_place(out.path)) {
      if (::access(out.path.c_str(), W_OK) != 0)
        throw IoError(out.path + ": cannot write " + out.option + ": " + std::strerror(errno));
      continue;
    }
    const fs::path parent = fs::path(canonical_text(out.path)).parent_path();
    const fs::path target = probe_target(parent, planned);
    if (target.empty())
      throw UsageError("cannot write '" + out.path + "' (" + out.option + "): directory '" +
                       parent.string() + "' does not exist");
    if (std::find(probed.begin(), probed.end(), target) != probed.end()) continue;
    probed.push_back(target);
    const std::string why = probe_directory(target);
    if (!why.empty())
      throw IoError(out.path + ": cannot write " + out.option + " into '" + target.string() +
                    "': " + why);
  }
}

void check_job_memory(std::int64_t patches, const JobPlan& plan) {
  const auto limit = job_memory_limit(plan.max_memory);
  if (!limit) return;
  const double mesh = mesh_peak_bytes(patches);
  const double ff = plan.ff ? form_factor_peak_bytes(patches, *plan.ff) : 0.0;
  // direct's factorisation at the all-pairs bound (nnz = N^2: a dense LU); for a loaded F its
  // real nnz is checked by the solver once the file is read.
  const bool direct = plan.direct && plan.ff && patches <= std::numeric_limits<std::int32_t>::max();
  const auto n = static_cast<std::int32_t>(direct ? patches : 0);
  const std::int64_t all_pairs = static_cast<std::int64_t>(n) * n;
  const std::string why = direct ? direct_refusal(n, all_pairs, limit->bytes, limit->source) : "";
  if (!why.empty()) throw UsageError(why);
  const double lu = direct ? direct_memory_bytes(n, all_pairs) : 0.0;
  // The medium's zones, and the copy of the patches' block the extended F makes.
  const double medium =
      plan.medium ? medium_peak_bytes(patches, *plan.medium, plan.medium_rays) + ff : 0.0;
  if (mesh + ff + lu + medium <= limit->bytes) return;
  throw UsageError(
      "this job needs about " + format_bytes(mesh + ff + lu + medium) + " (" +
      std::to_string(patches) + " patches: mesh " + format_bytes(mesh) +
      (plan.ff ? ", form factors " + format_bytes(ff) + " at the all-pairs bound" : "") +
      (direct ? ", direct's LU " + format_bytes(lu) : "") +
      (plan.medium ? ", the medium's zones " + format_bytes(medium) +
                         " (fewer --voxels or --medium-rays lower it)"
                   : "") +
      ") but the limit is " + format_bytes(limit->bytes) + " (" + limit->source +
      "): use fewer --patches or a larger --max-edge (--threshold does not lower the "
      "peak), or set --max-memory / LAMBERT_MAX_MEMORY (0 = no check)");
}

void check_options_read(const RunArgs& args, const Selection& selection) {
  check_option_scopes(args.given, selection);
}

void apply_run_options(const RunArgs& args) {
  set_log_level(args.quiet ? LogLevel::Quiet : args.verbose ? LogLevel::Verbose : LogLevel::Normal);
}

OutputPrefix plan_output_prefix(const std::string& output, const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const bool exists = fs::is_directory(output, ec);
  if (!output.empty() && (output.back() == '/' || exists))
    return {(fs::path(output) / name).string(), exists ? "" : output};
  return {output, ""};
}

namespace {

void create_folder(const std::string& folder) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw IoError(folder + ": cannot create directory: " + ec.message());
}

}  // namespace

std::string output_prefix(const std::string& output, const std::string& name) {
  const OutputPrefix p = plan_output_prefix(output, name);
  if (!p.folder.empty()) create_folder(p.folder);
  return p.prefix;
}

std::string summary_beside(const std::string& file) {
  if (writes_in_place(file)) return "";
  std::filesystem::path p(file);
  if (p.extension() == ".csv") return p.replace_extension(".json").string();
  return file + ".json";
}

Scene load_scene_file(const SceneArgs& args) {
  LoadOptions options = args.load;
  for (const auto& text : args.emit) {
    EmitRule rule;
    const std::string why = parse_emit(text, rule);
    if (!why.empty()) throw UsageError("--emit: " + why);
    options.emit.push_back(rule);
  }
  const std::string path = args.scene.empty() ? builtin_cornell_box_path() : args.scene;
  LoadReport report;
  Scene scene = load_scene_path(path, &report, options);
  if (args.default_reflectance_given && !report.default_material_used)
    throw UsageError("--default-reflectance does not apply: every face of " + path +
                     " has a defined material");
  if (!args.sky.empty()) {
    LAMBERT_CHECK(args.sky.size() == 3, "--sky takes R,G,B");
    scene.daylight.sky = Eigen::Vector3d(args.sky[0], args.sky[1], args.sky[2]);
  }
  if (!args.sun.empty()) {
    const std::string why = parse_sun(args.sun, scene.daylight);
    if (!why.empty()) throw UsageError("--sun: " + why);
  }
  return scene;
}

Scene load_checked_scene(const SceneArgs& args, const JobPlan& plan) {
  SceneArgs quiet = args;  // a scene that must emit is refused below, not warned about
  if (args.require_emitter) quiet.load.warn_without_emitter = false;
  Scene scene = load_scene_file(quiet);
  const bool medium_emits =
      plan.medium && plan.medium->emission.size() > 0 && plan.medium->emission.maxCoeff() > 0.0;
  const bool emits = std::any_of(scene.surfaces.begin(), scene.surfaces.end(), [&](const auto& s) {
    return scene.materials[s.material].emits();
  });
  if (args.require_emitter && !emits && !medium_emits && !scene.daylight.any()) {
    const std::string path = args.scene.empty() ? builtin_cornell_box_path() : args.scene;
    throw UsageError(path +
                     ": nothing emits (no material with Ke > 0, no --medium-emission, no --sky "
                     "or --sun): B would be zero everywhere; make surfaces emit with --emit "
                     "NAME_OR_GLOB=R,G,B (`lambert info " +
                     (args.scene.empty() ? std::string() : args.scene + " ") +
                     "--list-surfaces` lists the names) or light the scene with --sky R,G,B "
                     "or --sun DX,DY,DZ,R,G,B");
  }
  // Refused before any work (daylight_sources refuses it again for the library's callers).
  if (scene.daylight.any())
    for (const Surface& s : scene.surfaces)
      if (scene.materials[s.material].specular.any())
        throw UsageError(
            "--sky and --sun do not follow light through mirrors and glass yet, "
            "and surface '" +
            s.name + "' of " + scene.source + " is specular");
  std::vector<NamedFile> inputs = plan.inputs;
  for (size_t k = 0; k < scene.files.size(); ++k) {
    const std::string& f = scene.files[k];
    const bool camera = std::filesystem::path(f).extension() == ".camera";
    inputs.push_back({k == 0 ? "scene" : camera ? "camera sidecar" : "material library", f});
  }
  check_job_files(inputs, plan.outputs, plan.folders);
  for (const auto& folder : plan.folders) create_folder(folder);
  return scene;
}

MeshOptions mesh_options(const SceneArgs& args) {
  MeshOptions mo;
  mo.max_edge = args.max_edge;
  mo.target_patches = args.patches > 0 || args.max_edge > 0 ? args.patches : args.default_patches;
  mo.surface_floor = args.surface_floor;
  mo.discontinuity = args.discontinuity;
  mo.discontinuity_sources = args.discontinuity_sources;
  return mo;
}

LoadedScene load_scene(const SceneArgs& args, const JobPlan& plan) {
  LoadedScene out;
  out.scene = load_checked_scene(args, plan);
  MeshOptions mo = mesh_options(args);
  const MeshPlan mesh_plan = plan_mesh(out.scene, mo);
  if (!mesh_plan.note.empty()) log_info(mesh_plan.note);
  if (!mesh_plan.floor_note.empty()) log_info(mesh_plan.floor_note);
  if (mesh_plan.patches <= kMaxPatches) check_job_memory(mesh_plan.patches, plan);
  // Planned: mesh_scene need not search again (discontinuity meshing plans its own
  // correction from the target).
  if (!mo.discontinuity) mo.max_edge = mesh_plan.max_edge;
  out.mesh = mesh_scene(out.scene, mo);
  out.max_edge = out.mesh.max_edge;
  out.discontinuity = mo.discontinuity;
  return out;
}

const Bvh& scene_bvh(const LoadedScene& scene, int threads) {
  if (!scene.bvh) scene.bvh = std::make_shared<const Bvh>(scene.mesh, threads);
  return *scene.bvh;
}

}  // namespace lambert
