#include "io/soup_builder.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numeric>

#include "core/error.hpp"
#include "core/log.hpp"
#include "geometry/polygon.hpp"
#include "io/camera_file.hpp"
#include "io/surface_split.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;

// As the OBJ loader (io/obj_loader.cpp): a polygon off its mean plane by more than this
// fraction of its extent is split; more corners than kMaxSplitCorners are refused.
constexpr double kPlanarityRelTol = 1e-4;
constexpr size_t kMaxSplitCorners = 1000;

std::int32_t root(std::vector<std::int32_t>& parent, std::int32_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

}  // namespace

std::string read_file_bytes(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path + ": cannot open: file not found");
  if (fs::is_directory(path, ec)) throw IoError(path + ": cannot open: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(path + ": read error");
  return bytes;
}

void add_camera_sidecar(Scene& scene, const std::string& path) {
  scene.files = {path};
  const fs::path camera_path = fs::path(path).replace_extension(".camera");
  std::error_code ec;
  if (fs::exists(camera_path, ec)) {
    scene.camera = read_camera_file(camera_path.string());
    scene.files.push_back(camera_path.string());
  }
}

std::string stem_of(const std::string& name, const std::string& fallback) {
  const std::string stem = fs::path(name).stem().string();
  return stem.empty() ? fallback : stem;
}

SceneBuilder::SceneBuilder(const std::string& name, LoadReport& report)
    : name_(name), report_(report) {
  scene_.source = name;
}

void SceneBuilder::add_facet(const std::array<Eigen::Vector3d, 3>& c,
                             const Eigen::Vector3d& stored_normal, std::int32_t surface, int line) {
  const std::vector<Eigen::Vector3d> poly(c.begin(), c.end());
  if (is_degenerate_polygon(poly)) {
    ++report_.degenerate_faces_dropped;
    return;
  }
  // Only the side matters to radiosity (fronts emit and receive): a stored normal in the
  // back half-space of the winding normal disagrees; a tilted one (rounded, or averaged by
  // the exporter) does not. A zero normal means "not given".
  if (stored_normal.dot(newell_normal(poly)) < 0.0) ++flipped_;
  Face f;
  f.surface = surface;
  f.line = line;
  for (const auto& p : c) f.vertices.push_back(vertex(p));
  scene_.faces.push_back(std::move(f));
}

void SceneBuilder::add_polygon(const std::vector<Eigen::Vector3d>& poly, std::int32_t surface,
                               const std::string& where) {
  if (is_degenerate_polygon(poly)) {
    ++report_.degenerate_faces_dropped;
    return;
  }
  Face f;
  f.surface = surface;
  for (const auto& p : poly) f.vertices.push_back(vertex(p));
  const double extent = polygon_extent(poly), off = planarity_deviation(poly);
  if (off <= kPlanarityRelTol * extent) {
    scene_.faces.push_back(std::move(f));
    return;
  }
  if (poly.size() > kMaxSplitCorners)
    throw SceneError(name_ + ": " + where + ": non-planar polygon with " +
                     std::to_string(poly.size()) + " corners (more than " +
                     std::to_string(kMaxSplitCorners) + " cannot be split into triangles)");
  if (report_.nonplanar_faces_split++ == 0) first_split_ = where;
  if (off / extent > worst_split_relative_) {
    worst_split_relative_ = off / extent;
    worst_split_ = where;
  }
  for (const auto& t : triangulate(poly)) {
    Face tri = f;
    tri.vertices = {f.vertices[t[0]], f.vertices[t[1]], f.vertices[t[2]]};
    scene_.faces.push_back(tri);
  }
}

std::int32_t SceneBuilder::surface(const std::string& surface_name) {
  auto [it, added] =
      surface_of_.emplace(surface_name, static_cast<std::int32_t>(scene_.surfaces.size()));
  if (added) scene_.surfaces.push_back({surface_name, 0});
  return it->second;
}

void SceneBuilder::assign_components(const std::string& fallback_stem) {
  std::vector<std::int32_t> parent(scene_.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const Face& f : scene_.faces)
    for (size_t k = 1; k < f.vertices.size(); ++k)
      parent[root(parent, f.vertices[k])] = root(parent, f.vertices[0]);
  std::map<std::int32_t, std::int32_t> component;  // root -> number, in first-face order
  for (const Face& f : scene_.faces) {
    const std::int32_t r = root(parent, f.vertices[0]);
    if (!component.count(r)) component.emplace(r, static_cast<std::int32_t>(component.size()));
  }
  const std::string stem = stem_of(name_, fallback_stem);
  // Surfaces are created in first-face order so that surface k is component k.
  std::vector<std::int32_t> order(component.size());
  for (const auto& [r, k] : component) order[k] = r;
  std::vector<std::int32_t> surface_of(component.size());
  for (size_t k = 0; k < order.size(); ++k)
    surface_of[k] = surface(order.size() == 1 ? stem : stem + "_" + std::to_string(k + 1));
  for (Face& f : scene_.faces) f.surface = surface_of[component[root(parent, f.vertices[0])]];
}

Scene SceneBuilder::finish(const LoadOptions& options, int up) {
  if (report_.degenerate_faces_dropped > 0)
    warn(name_ + ": " + std::to_string(report_.degenerate_faces_dropped) +
         " zero-area facet(s) dropped");
  if (report_.nonplanar_faces_split > 0)
    warn(name_ + ": " + std::to_string(report_.nonplanar_faces_split) +
         " non-planar polygon(s) (the first: " + first_split_ +
         ") split into triangles; the "
         "worst (" +
         worst_split_ + ") is off its plane by " + std::to_string(100.0 * worst_split_relative_) +
         " % of its size");
  if (flipped_ > 0)
    warn(name_ + ": " + std::to_string(flipped_) +
         " facet(s) store a normal opposite to their vertex order; the vertex order "
         "(counter-clockwise about the front) is used");
  if (scene_.faces.empty()) throw SceneError(name_ + ": empty scene: no facets with positive area");
  if (options.split_angle >= 0.0)
    split_surfaces_at_feature_edges(scene_, options.split_angle, name_);
  for (const std::string& w : coincident_face_warnings(scene_, name_, report_.coincident_faces))
    warn(w);
  if (scene_.materials.empty()) {  // STL, PLY: every surface takes the default material
    scene_.materials.push_back({"default", options.default_reflectance, Eigen::Vector3d::Zero()});
    report_.default_material_used = true;
  }
  apply_emit(options.emit, name_, scene_);
  for (const auto& s : scene_.surfaces)
    report_.has_emitter = report_.has_emitter || scene_.materials[s.material].emits();
  const auto [lo, hi] = scene_.bounds();
  // The OBJ loader's floor (io/obj_loader.cpp): distances^4 must stay normal doubles.
  if ((hi - lo).norm() < 1e-50)
    throw SceneError(name_ +
                     ": scene extent below 1e-50, where form factors underflow: "
                     "rescale the scene");
  scene_.camera = three_quarter_camera(lo, hi, up);
  return std::move(scene_);
}

std::int32_t SceneBuilder::vertex(const Eigen::Vector3d& p) {
  Eigen::Vector3d q = p + Eigen::Vector3d::Zero();  // -0 and +0 are one position
  const std::string key(reinterpret_cast<const char*>(q.data()), sizeof(double) * 3);
  auto [it, added] = index_.emplace(key, static_cast<std::int32_t>(scene_.vertices.size()));
  if (added) scene_.vertices.push_back(p);
  return it->second;
}

void SceneBuilder::warn(const std::string& msg) {
  log_warn(msg);
  report_.warnings.push_back(msg);
}

}  // namespace lambert
