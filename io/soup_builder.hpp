#pragma once
// The scene of a file without groups or materials (STL, PLY): corners shared by exact
// position, faces checked as every loader checks them (zero area dropped, a stored normal
// against the winding counted, non-planar polygons split), surfaces by name or by connected
// component, the default material, the --emit rules and the default view.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "geometry/scene.hpp"
#include "io/obj_loader.hpp"

namespace lambert {

/// The whole content of `path` (IoError naming it when it is missing, a directory or
/// unreadable).
std::string read_file_bytes(const std::string& path);

/// The file name's stem ("part" for "dir/part.stl"), `fallback` when it has none.
std::string stem_of(const std::string& name, const std::string& fallback);

/// Records `path` as the scene's file and reads the camera sidecar `<stem>.camera` beside it
/// when there is one (it then frames the images and is an input no output may overwrite).
void add_camera_sidecar(Scene& scene, const std::string& path);

class SceneBuilder {
 public:
  SceneBuilder(const std::string& name, LoadReport& report);

  /// Adds a triangle to `surface` (-1: assigned later by assign_components) from source line
  /// `line` (0: none); `stored_normal` (zero: none) is checked against the winding.
  void add_facet(const std::array<Eigen::Vector3d, 3>& c, const Eigen::Vector3d& stored_normal,
                 std::int32_t surface, int line);
  /// Adds a polygon (corners counter-clockwise about its front); one off its plane by more
  /// than 1e-4 of its size is split into triangles (counted and warned about once, with the
  /// worst). `where` names it in messages ("face 12").
  void add_polygon(const std::vector<Eigen::Vector3d>& corners, std::int32_t surface,
                   const std::string& where);
  /// The surface named `surface_name` (created on first use).
  std::int32_t surface(const std::string& surface_name);
  /// One surface per connected component (faces sharing a corner position), named after the
  /// file's stem (stem_1, stem_2, ... when there are several), in first-face order.
  void assign_components(const std::string& fallback_stem);
  Scene& scene() { return scene_; }
  /// Warnings, the default material (when the caller added no materials: every surface
  /// takes it), the emit rules, the default view (`up`: 1 = y, 2 = z);
  /// refuses a scene without faces or of an extent below 1e-50.
  Scene finish(const LoadOptions& options, int up);

 private:
  std::int32_t vertex(const Eigen::Vector3d& p);
  void warn(const std::string& msg);

  std::string name_;
  LoadReport& report_;
  Scene scene_;
  std::unordered_map<std::string, std::int32_t> index_;
  std::map<std::string, std::int32_t> surface_of_;
  int flipped_ = 0;
  std::string first_split_, worst_split_;
  double worst_split_relative_ = 0.0;
};

}  // namespace lambert
