#include "io/obj_loader.hpp"

#include <tiny_obj_loader.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "core/log.hpp"
#include "geometry/polygon.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;

// A face whose area is below this fraction of its squared diameter is degenerate: its
// normal is not defined to better than ~1e-5 relative in double precision (the cross
// product of near-parallel edges loses that many digits), so it cannot be a patch.
constexpr double kDegenerateRelArea = 1e-10;
// Vertices farther than this fraction of the polygon diameter from its mean plane make it
// non-planar. Measured geometry is rarely better than 1e-4 relative (the Cornell box's red
// wall is off by 0.8 mm in 559 mm = 1.4e-3); below it, form factors change by < 1e-4.
constexpr double kPlanarityRelTol = 1e-4;

std::string where(const std::string& file, int line) {
  return line > 0 ? file + ":" + std::to_string(line) : file;
}

std::ifstream open_or_throw(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path + ": cannot open: file not found");
  if (fs::is_directory(path, ec)) throw IoError(path + ": cannot open: is a directory");
  std::ifstream in(path);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  return in;
}

bool parse_double(const std::string& tok, double& out) {
  if (tok.empty()) return false;
  const char* begin = tok.c_str();
  char* end = nullptr;
  errno = 0;
  out = std::strtod(begin, &end);
  return end == begin + tok.size();
}

// Line-level facts the loader needs for messages (tinyobjloader keeps no line numbers).
struct ObjLines {
  std::vector<int> face_lines;                             // line of the k-th face
  std::vector<std::pair<int, std::string>> usemtl;         // (line, name)
  std::vector<std::pair<int, std::string>> mtllib;         // (line, file)
  int first_face_without_material = 0;
};

// Scans the OBJ for syntax errors that tinyobjloader would silently accept.
ObjLines scan_obj(const std::string& path) {
  std::ifstream in = open_or_throw(path);
  ObjLines out;
  static const std::set<std::string> kIgnored = {"vt", "vn", "vp", "s", "l", "p", "cstype",
                                                 "deg", "curv", "curv2", "surf", "parm",
                                                 "trim", "hole", "end", "bmat", "step",
                                                 "mg", "lod", "shadow_obj", "trace_obj",
                                                 "ctech", "stech", "o", "g"};
  std::string line;
  int lineno = 0;
  std::int64_t nverts = 0;
  bool have_material = false;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    if (!(ls >> key) || key[0] == '#') continue;
    const std::string at = where(path, lineno);
    if (key == "v") {
      double c[3];
      std::string tok;
      for (double& x : c) {
        if (!(ls >> tok) || !parse_double(tok, x))
          throw SceneError(at + ": malformed vertex: expected 3 numbers");
        if (!std::isfinite(x)) throw SceneError(at + ": vertex coordinate '" + tok + "' is not finite");
      }
      ++nverts;
    } else if (key == "f") {
      std::string tok;
      int count = 0;
      while (ls >> tok) {
        const std::string idx = tok.substr(0, tok.find('/'));
        char* end = nullptr;
        const long v = std::strtol(idx.c_str(), &end, 10);
        if (idx.empty() || *end != '\0')
          throw SceneError(at + ": malformed face index '" + tok + "'");
        const std::int64_t resolved = v > 0 ? v : nverts + v + 1;
        if (v == 0 || resolved < 1 || resolved > nverts)
          throw SceneError(at + ": face index " + std::to_string(v) + " out of range (" +
                           std::to_string(nverts) + " vertices defined so far)");
        ++count;
      }
      if (count < 3) throw SceneError(at + ": face has " + std::to_string(count) + " vertices, needs at least 3");
      if (!have_material && out.first_face_without_material == 0) out.first_face_without_material = lineno;
      out.face_lines.push_back(lineno);
    } else if (key == "usemtl") {
      std::string name;
      if (!(ls >> name)) throw SceneError(at + ": usemtl without a material name");
      out.usemtl.emplace_back(lineno, name);
      have_material = true;
    } else if (key == "mtllib") {
      std::string name;
      if (!(ls >> name)) throw SceneError(at + ": mtllib without a file name");
      out.mtllib.emplace_back(lineno, name);
    } else if (!kIgnored.count(key)) {
      throw SceneError(at + ": malformed OBJ: unknown statement '" + key + "'");
    }
  }
  if (in.bad()) throw IoError(path + ": read error");
  return out;
}

// Lines of each material's Kd / Ke statements in the MTL files.
struct MtlLines {
  std::map<std::string, std::pair<std::string, int>> kd, ke, def;  // name -> (file, line)
};

MtlLines scan_mtl(const std::string& path) {
  MtlLines out;
  std::ifstream in = open_or_throw(path);
  std::string line, current;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    std::istringstream ls(line);
    std::string key;
    if (!(ls >> key) || key[0] == '#') continue;
    if (key == "newmtl") {
      ls >> current;
      out.def[current] = {path, lineno};
    } else if (key == "Kd" || key == "Ke") {
      std::string tok;
      double x;
      for (int c = 0; c < 3; ++c) {
        if (!(ls >> tok) || !parse_double(tok, x))
          throw SceneError(where(path, lineno) + ": malformed " + key + ": expected 3 numbers");
        if (!std::isfinite(x))
          throw SceneError(where(path, lineno) + ": material '" + current + "': " + key +
                           " value '" + tok + "' must be finite");
      }
      (key == "Kd" ? out.kd : out.ke)[current] = {path, lineno};
    }
  }
  return out;
}

Material convert_material(const tinyobj::material_t& m, const MtlLines& lines,
                          const std::string& obj_path) {
  Material mat;
  mat.name = m.name;
  for (int c = 0; c < 3; ++c) {
    mat.rho[c] = m.diffuse[c];
    mat.emission[c] = m.emission[c];
  }
  auto at = [&](const std::map<std::string, std::pair<std::string, int>>& table) {
    auto it = table.find(m.name);
    if (it != table.end()) return where(it->second.first, it->second.second);
    auto def = lines.def.find(m.name);
    return def != lines.def.end() ? where(def->second.first, def->second.second) : obj_path;
  };
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(mat.rho[c]) || mat.rho[c] < 0.0 || mat.rho[c] >= 1.0) {
      std::ostringstream msg;
      msg << at(lines.kd) << ": material '" << m.name << "': reflectance Kd " << mat.rho.transpose()
          << " must lie in [0, 1) in every channel (rho >= 1 makes I - rho F singular: the "
             "radiosity system has no solution)";
      throw SceneError(msg.str());
    }
    if (!std::isfinite(mat.emission[c]) || mat.emission[c] < 0.0) {
      std::ostringstream msg;
      msg << at(lines.ke) << ": material '" << m.name << "': emission Ke "
          << mat.emission.transpose() << " must be finite and >= 0";
      throw SceneError(msg.str());
    }
  }
  return mat;
}

Camera read_camera(const std::string& path) {
  std::ifstream in = open_or_throw(path);
  Camera cam;
  double focal = 0, film = 0, vfov = 0;
  std::string line;
  int lineno = 0;
  bool have_eye = false, have_at = false;
  while (std::getline(in, line)) {
    ++lineno;
    std::istringstream ls(line);
    std::string key;
    if (!(ls >> key) || key[0] == '#') continue;
    auto vec = [&](Eigen::Vector3d& v) {
      if (!(ls >> v.x() >> v.y() >> v.z()) || !v.allFinite())
        throw SceneError(where(path, lineno) + ": '" + key + "' needs 3 finite numbers");
    };
    auto num = [&](double& x) {
      if (!(ls >> x) || !(x > 0) || !std::isfinite(x))
        throw SceneError(where(path, lineno) + ": '" + key + "' needs a positive number");
    };
    if (key == "eye") { vec(cam.eye); have_eye = true; }
    else if (key == "look_at") { vec(cam.look_at); have_at = true; }
    else if (key == "up") vec(cam.up);
    else if (key == "focal_mm") num(focal);
    else if (key == "film_mm") num(film);
    else if (key == "vfov") num(vfov);
    else throw SceneError(where(path, lineno) + ": unknown camera key '" + key + "'");
  }
  if (!have_eye || !have_at) throw SceneError(path + ": camera needs 'eye' and 'look_at'");
  if (vfov >= 180.0)
    throw SceneError(path + ": 'vfov' must be below 180 degrees (a pinhole cannot see more)");
  if (focal > 0 && film > 0) vfov = 2.0 * std::atan(0.5 * film / focal) * 180.0 / M_PI;
  if (vfov > 0) cam.vfov_degrees = vfov;
  cam.defined = true;
  return cam;
}

}  // namespace

std::string builtin_cornell_box_path() {
  if (const char* dir = std::getenv("LAMBERT_DATA_DIR"))
    return (fs::path(dir) / "cornell_box" / "cornell_box.obj").string();
  return (fs::path(LAMBERT_DATA_DIR) / "cornell_box" / "cornell_box.obj").string();
}

Scene load_obj(const std::string& path, LoadReport* report) {
  const ObjLines lines = scan_obj(path);
  const fs::path base = fs::path(path).parent_path();
  MtlLines mtl_lines;
  for (const auto& [lineno, lib] : lines.mtllib) {
    const fs::path mtl = base / lib;
    std::error_code ec;
    if (!fs::exists(mtl, ec))
      throw SceneError(where(path, lineno) + ": material library '" + lib + "' not found");
    MtlLines more = scan_mtl(mtl.string());
    mtl_lines.kd.insert(more.kd.begin(), more.kd.end());
    mtl_lines.ke.insert(more.ke.begin(), more.ke.end());
    mtl_lines.def.insert(more.def.begin(), more.def.end());
  }

  tinyobj::ObjReaderConfig config;
  config.triangulate = false;
  config.vertex_color = false;
  config.mtl_search_path = base.string();
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(path, config)) {
    std::string err = reader.Error();
    while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
    for (char& ch : err) if (ch == '\n') ch = ' ';
    throw SceneError(path + ": malformed OBJ: " + err);
  }
  const auto& attrib = reader.GetAttrib();
  const auto& shapes = reader.GetShapes();
  const auto& materials = reader.GetMaterials();

  Scene scene;
  scene.source = path;
  std::map<std::string, int> material_index;
  for (const auto& m : materials) {
    material_index[m.name] = static_cast<int>(scene.materials.size());
    scene.materials.push_back(convert_material(m, mtl_lines, path));
  }
  for (const auto& [lineno, name] : lines.usemtl) {
    if (!material_index.count(name))
      throw SceneError(where(path, lineno) + ": material '" + name + "' is not defined" +
                       (lines.mtllib.empty() ? " (no mtllib)" : " in the material library"));
  }
  if (lines.first_face_without_material > 0)
    throw SceneError(where(path, lines.first_face_without_material) +
                     ": face has no material (no usemtl before it)");

  for (size_t v = 0; v * 3 + 2 < attrib.vertices.size(); ++v)
    scene.vertices.emplace_back(attrib.vertices[3 * v], attrib.vertices[3 * v + 1],
                                attrib.vertices[3 * v + 2]);

  // Surfaces: one per (shape name, material); the material is appended to the name only
  // when a shape uses several.
  std::map<std::pair<std::string, int>, std::int32_t> surface_of;
  size_t face_counter = 0;
  int dropped = 0, split = 0;
  for (size_t s = 0; s < shapes.size(); ++s) {
    const auto& mesh = shapes[s].mesh;
    const std::string shape_name =
        shapes[s].name.empty() ? "surface" + std::to_string(s) : shapes[s].name;
    std::set<int> mats(mesh.material_ids.begin(), mesh.material_ids.end());
    size_t offset = 0;
    for (size_t f = 0; f < mesh.num_face_vertices.size(); ++f) {
      const int nv = mesh.num_face_vertices[f];
      const int line = face_counter < lines.face_lines.size() ? lines.face_lines[face_counter] : 0;
      ++face_counter;
      const int mat = mesh.material_ids[f];
      if (mat < 0 || mat >= static_cast<int>(scene.materials.size()))
        throw SceneError(where(path, line) + ": face has no valid material");
      Face face;
      face.line = line;
      std::vector<Eigen::Vector3d> poly;
      std::set<int> distinct;
      for (int k = 0; k < nv; ++k) {
        const int vi = mesh.indices[offset + k].vertex_index;
        // A corner repeating the previous one (same index or position) adds nothing to
        // the polygon but would leave a zero-length edge: collapse it.
        if (!poly.empty() && (vi == face.vertices.back() || scene.vertices[vi] == poly.back()))
          continue;
        face.vertices.push_back(vi);
        distinct.insert(vi);
        poly.push_back(scene.vertices[vi]);
      }
      while (poly.size() > 1 && poly.back() == poly.front()) {
        poly.pop_back();
        distinct.erase(face.vertices.back());
        face.vertices.pop_back();
      }
      offset += nv;
      const double diam = polygon_diameter(poly);
      if (distinct.size() < 3 || polygon_area(poly) <= kDegenerateRelArea * diam * diam) {
        ++dropped;
        log_debug(where(path, line) + ": zero-area face dropped");
        continue;
      }
      const auto key = std::make_pair(shape_name, mat);
      auto it = surface_of.find(key);
      if (it == surface_of.end()) {
        const std::string name =
            mats.size() > 1 ? shape_name + "/" + scene.materials[mat].name : shape_name;
        it = surface_of.emplace(key, static_cast<std::int32_t>(scene.surfaces.size())).first;
        scene.surfaces.push_back({name, mat});
      }
      face.surface = it->second;
      if (planarity_deviation(poly) > kPlanarityRelTol * diam) {
        ++split;
        log_warn(where(path, line) + ": non-planar polygon (off its plane by " +
                 std::to_string(planarity_deviation(poly)) + ") split into triangles");
        for (const auto& t : triangulate(poly)) {
          Face tri = face;
          tri.vertices = {face.vertices[t[0]], face.vertices[t[1]], face.vertices[t[2]]};
          scene.faces.push_back(tri);
        }
        continue;
      }
      scene.faces.push_back(std::move(face));
    }
  }
  if (dropped > 0) log_warn(path + ": " + std::to_string(dropped) + " zero-area face(s) dropped");
  if (scene.faces.empty()) throw SceneError(path + ": empty scene: no faces with positive area");

  bool emits = false;
  for (const auto& s : scene.surfaces) emits = emits || scene.materials[s.material].emits();
  if (!emits) log_warn(path + ": no emitter (no material with Ke > 0): the radiosity is zero");

  const fs::path camera_path = fs::path(path).replace_extension(".camera");
  std::error_code ec;
  if (fs::exists(camera_path, ec)) {
    scene.camera = read_camera(camera_path.string());
  } else {
    const auto [lo, hi] = scene.bounds();
    scene.camera = framing_camera(lo, hi);
  }
  if (report) *report = {dropped, split, emits};
  return scene;
}

}  // namespace lambert
