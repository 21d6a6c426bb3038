#pragma once
// Wavefront OBJ + MTL scene loading (lambert's own parser, io/obj_parser.hpp), with
// validation, documented defaults and command-line overrides.

#include <Eigen/Core>
#include <functional>
#include <istream>
#include <memory>
#include <string>
#include <vector>

#include "geometry/scene.hpp"

namespace lambert {

/// `--emit PATTERN=R,G,B`: surfaces whose name, or whose material's name, matches the glob
/// `pattern` (`*`, `?`, `[...]`) emit radiosity `emission`.
struct EmitRule {
  std::string pattern;
  Eigen::Vector3d emission = Eigen::Vector3d::Zero();
};

/// How to load: what to assume where a file says nothing, and overrides.
struct LoadOptions {
  bool strict = false;  ///< refuse missing/undefined materials and Kd = 1 instead of warning
  Eigen::Vector3d default_reflectance = Eigen::Vector3d::Constant(0.5);  ///< default material
  double max_reflectance = 0.0;  ///< > 0: Kd channels above it are clamped to it, with a warning
  std::vector<EmitRule> emit;    ///< applied in order (a later rule overrides an earlier one)
  /// Each face whose corners all have colours (`v x y z r g b`) gets their mean as its
  /// reflectance (Face::rho) instead of its material's Kd.
  bool vertex_colors_as_reflectance = false;
  /// --split-angle DEG: >= 0 splits each surface at edges where the faces' normals turn by
  /// more than DEG degrees (io/surface_split.hpp); < 0: off (surfaces as the file has them).
  double split_angle = -1.0;
  /// Warn when nothing emits (radiosity would be zero); off for `lambert heat`, whose
  /// sources are temperatures from its surfaces file.
  bool warn_without_emitter = true;
};

/// What the loader had to repair, default or skip (each also logged as a warning).
struct LoadReport {
  int degenerate_faces_dropped = 0;
  int nonplanar_faces_split = 0;
  int skipped_statements = 0;  ///< statements (and vertex colours/weights) radiosity does not use
  int coincident_faces = 0;    ///< faces with exactly the corners of an earlier face
  bool has_emitter = false;
  /// Some face takes the default material (no or an undefined material; every STL facet),
  /// whose reflectance --default-reflectance sets.
  bool default_material_used = false;
  std::vector<std::string> warnings;  ///< every warning, in the order it was logged
};

/// One warning per pair of surfaces with faces of exactly the same corners (their area counts
/// twice), naming the file `name` and the lines; adds the number of such faces to
/// `coincident_faces`. OBJ and STL loaders share it. O(faces) expected (hashed corners).
std::vector<std::string> coincident_face_warnings(const Scene& scene, const std::string& name,
                                                  int& coincident_faces);

/// A material library opened for an `mtllib` statement: `stream` is null when there is no
/// such library; `name` is used in messages.
struct MtlFile {
  std::unique_ptr<std::istream> stream;
  std::string name;
};
/// Opens the material library an `mtllib` statement names.
using MtlOpener = std::function<MtlFile(const std::string& library)>;

/// Loads an OBJ scene. `Kd` is the reflectance rho, `Ke` the emitted radiosity E. Each
/// OBJ group/object (and material within it) becomes a named surface. A sidecar file
/// `<name>.camera` next to the OBJ, if present, gives the default camera. Material
/// libraries are looked up next to the OBJ. Throws IoError (missing/unreadable file),
/// SceneError (invalid content, "file:line: what") or UsageError (an --emit rule matching
/// nothing). docs/scenes.md says what is accepted, defaulted, skipped and refused.
Scene load_obj(const std::string& path, LoadReport* report = nullptr,
               const LoadOptions& options = {});

/// load_obj from a stream named `name`, with material libraries from `open_mtl` and no
/// camera sidecar (the camera frames the scene). For tests and fuzzing.
Scene load_obj_stream(std::istream& obj, const std::string& name, const MtlOpener& open_mtl,
                      LoadReport* report = nullptr, const LoadOptions& options = {});

/// `--emit`: each rule sets E on the material of every surface it matches by surface or
/// material name (a material also used by surfaces the rule does not match is copied first,
/// as `material@surface`). Throws UsageError for a rule matching nothing in `name`. Shared by
/// the OBJ and STL loaders.
void apply_emit(const std::vector<EmitRule>& rules, const std::string& name, Scene& scene);

/// Path of the built-in Cornell box scene.
std::string builtin_cornell_box_path();

}  // namespace lambert
