#include "io/obj_loader.hpp"

#include <fnmatch.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>

#include "core/error.hpp"
#include "core/log.hpp"
#include "geometry/polygon.hpp"
#include "io/camera_file.hpp"
#include "io/line_reader.hpp"
#include "io/mtl_parser.hpp"
#include "io/obj_parser.hpp"
#include "io/surface_split.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;

// Vertices farther than this fraction of the polygon extent from its mean plane make it
// non-planar. Measured geometry is rarely better than 1e-4 relative (the Cornell box's red
// wall is off by 0.8 mm in 559 mm = 1.4e-3); below it, form factors change by < 1e-4.
constexpr double kPlanarityRelTol = 1e-4;
// Non-planar polygons are split by ear clipping, O(n^2) to O(n^3) in their corner count:
// beyond this many corners (~1e9 operations in the worst case) they are refused instead.
constexpr size_t kMaxSplitCorners = 1000;
// Smallest accepted scene extent: distances^4 (see kMaxObjCoordinate) must stay normal
// doubles, (1e-50)^4 = 1e-200 > 2.2e-308.
constexpr double kMinSceneExtent = 1e-50;
// Names listed in one warning before "and N more".
constexpr size_t kMaxListed = 6;

std::string where(const std::string& file, int line) {
  return line > 0 ? file + ":" + std::to_string(line) : file;
}

// Shortest readable form of a number (6 significant digits, no trailing zeros).
std::string num(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

std::string rgb(const Eigen::Vector3d& c) { return num(c[0]) + " " + num(c[1]) + " " + num(c[2]); }

std::string list_names(const std::set<std::string>& names) {
  std::string out;
  size_t k = 0;
  for (const auto& n : names) {
    if (k == kMaxListed) return out + " and " + std::to_string(names.size() - k) + " more";
    out += (k++ ? ", '" : "'") + n + "'";
  }
  return out;
}

// Warnings go to the log and to the report; in --strict mode a refusal instead.
class Diagnostics {
 public:
  Diagnostics(bool strict, LoadReport& report) : strict_(strict), report_(report) {}
  void warn(const std::string& msg) {
    log_warn(msg);
    report_.warnings.push_back(msg);
  }
  // A default that --strict refuses: `refusal` is the error, `msg` the warning.
  void defaulted(const std::string& refusal, const std::string& msg) {
    if (strict_) throw SceneError(refusal);
    warn(msg);
  }
  bool strict() const { return strict_; }

 private:
  bool strict_;
  LoadReport& report_;
};

std::ifstream open_or_throw(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path + ": cannot open: file not found");
  if (fs::is_directory(path, ec)) throw IoError(path + ": cannot open: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  return in;
}

// The material libraries of all mtllib statements, parsed once each; a later definition
// of a name replaces an earlier one. A statement naming no library that opens is a
// default (warning), unless its whole rest or each of its tokens opens.
std::vector<MtlMaterial> read_libraries(const ObjData& obj, const std::string& name,
                                        const MtlOpener& open_mtl, Diagnostics& diag) {
  std::vector<MtlMaterial> defs;
  std::map<std::string, size_t> index;
  std::set<std::string> opened;
  auto read = [&](MtlFile f) {
    if (!opened.insert(f.name).second) return;
    for (auto& m : parse_mtl(*f.stream, f.name)) {
      auto [it, added] = index.emplace(m.name, defs.size());
      if (added) {
        defs.push_back(std::move(m));
        continue;
      }
      diag.warn(where(m.file, m.line) + ": material '" + m.name + "' defined again (first at " +
                where(defs[it->second].file, defs[it->second].line) + "): this one is used");
      defs[it->second] = std::move(m);
    }
  };
  for (const auto& lib : obj.mtllibs) {
    MtlFile whole = open_mtl(lib.rest);
    if (whole.stream) {
      read(std::move(whole));
      continue;
    }
    for (const auto& tok : lib.tokens) {
      MtlFile f = tok == lib.rest ? MtlFile{} : open_mtl(tok);
      if (f.stream) {
        read(std::move(f));
        continue;
      }
      const std::string at = where(name, lib.line) + ": material library '" + tok + "' not found";
      diag.defaulted(at, at + ": the materials it would define get the default");
    }
  }
  return defs;
}

// MTL illum models: 3, 5 and 8 reflect (a mirror of reflectance Ks), 4, 6, 7 and 9 refract
// (a dielectric of index Ni, its refracted light filtered by Tf); the rest are diffuse (their
// Ks is a highlight, not a mirror).
bool mirror_illum(int illum) { return illum == 3 || illum == 5 || illum == 8; }
bool dielectric_illum(int illum) { return illum == 4 || illum == 6 || illum == 7 || illum == 9; }

// MTL statements the material's illum model does not use (for one warning). Ks with a
// diffuse illum (0-2: a Phong highlight, in nearly every exported file) is ignored silently.
struct Unused {
  std::set<std::string> transparency;  // d < 1 without refraction
};

// The specular part of an MTL material: a mirror needs Kd + Ks <= 1 per channel, a
// dielectric Kd = 0 (it reflects and transmits all it does not absorb).
Specular convert_specular(const MtlMaterial& m, const Material& mat, Unused& unused) {
  Specular sp;
  sp.shininess = m.ns;
  if (mirror_illum(m.illum)) {
    sp.reflectance = m.ks;
    const std::string at_ks = where(m.file, m.ks_line ? m.ks_line : m.line);
    if (m.ks.minCoeff() < 0.0 || m.ks.maxCoeff() > 1.0)
      throw SceneError(at_ks + ": material '" + m.name + "': specular reflectance Ks " +
                       rgb(m.ks) + " must lie in [0, 1] in every channel");
    if ((mat.rho + m.ks).maxCoeff() > 1.0)
      throw SceneError(at_ks + ": material '" + m.name + "': Kd " + rgb(mat.rho) + " + Ks " +
                       rgb(m.ks) + " exceeds 1 in some channel (the surface would reflect more "
                       "than it receives)");
  } else if (dielectric_illum(m.illum)) {
    sp.dielectric = true;
    sp.ior = m.ni;
    sp.transmission = m.tf;
    if (!(m.ni > 0.0))
      throw SceneError(where(m.file, m.ni_line ? m.ni_line : m.line) + ": material '" + m.name +
                       "': index of refraction Ni " + num(m.ni) + " of a dielectric (illum " +
                       std::to_string(m.illum) + ") must be > 0");
    if (mat.rho.maxCoeff() > 0.0)
      throw SceneError(where(m.file, m.kd_line ? m.kd_line : m.line) + ": material '" + m.name +
                       "': a dielectric (illum " + std::to_string(m.illum) + ") needs Kd 0: it "
                       "reflects (Fresnel) and refracts all the light it does not absorb, got Kd " +
                       rgb(mat.rho));
  }
  if (m.dissolve < 1.0 && !sp.dielectric) unused.transparency.insert(m.name);
  return sp;
}

// MTL material -> scene material: --max-reflectance clamps, then Kd must lie in [0, 1] and
// Ke be >= 0; the specular part from illum. Returns whether some channel of Kd is 1
// (lossless).
bool convert_material(const MtlMaterial& m, const LoadOptions& options, Material& mat,
                      std::set<std::string>& clamped, Unused& unused) {
  mat.name = m.name;
  mat.rho = m.kd;
  mat.emission = m.ke;
  const std::string at_kd = where(m.file, m.kd_line ? m.kd_line : m.line);
  if (options.max_reflectance > 0 && mat.rho.maxCoeff() > options.max_reflectance) {
    mat.rho = mat.rho.cwiseMin(options.max_reflectance);
    clamped.insert(m.name);
  }
  if (mat.rho.minCoeff() < 0.0 || mat.rho.maxCoeff() > 1.0)
    throw SceneError(at_kd + ": material '" + m.name + "': reflectance Kd " + rgb(mat.rho) +
                     " must lie in [0, 1] in every channel (rho > 1 reflects more than it "
                     "receives; --max-reflectance R clamps)");
  if (mat.emission.minCoeff() < 0.0)
    throw SceneError(where(m.file, m.ke_line ? m.ke_line : m.line) + ": material '" + m.name +
                     "': emission Ke " + rgb(mat.emission) + " must be finite and >= 0");
  mat.specular = convert_specular(m, mat, unused);
  const bool lossless = mat.rho.maxCoeff() == 1.0;
  if (lossless && options.strict)
    throw SceneError(at_kd + ": material '" + m.name + "': reflectance Kd " + rgb(mat.rho) +
                     " must lie in [0, 1) in every channel with --strict (rho = 1 makes I - rho "
                     "F singular in a closed enclosure that absorbs nothing)");
  return lossless;
}

// Scene materials and, per usemtl name of the OBJ, the scene material it resolves to.
struct Materials {
  std::vector<std::int32_t> of_use;  // ObjData::materials index -> scene material
  std::int32_t none = -1;            // faces without usemtl, and usemtl without a name
  std::vector<bool> undefined;       // per usemtl name: not in any library (defaulted)
  std::set<std::string> lossless;    // used materials with a channel of Kd = 1
};

Materials build_materials(const ObjData& obj, const std::vector<MtlMaterial>& defs,
                          const LoadOptions& options, const std::string& name,
                          Diagnostics& diag, Scene& scene) {
  Materials out;
  std::map<std::string, std::int32_t> by_name;
  std::set<std::string> clamped, lossless;
  Unused unused;
  for (const auto& m : defs) {
    Material mat;
    if (convert_material(m, options, mat, clamped, unused)) lossless.insert(m.name);
    by_name[m.name] = static_cast<std::int32_t>(scene.materials.size());
    scene.materials.push_back(mat);
  }
  if (!clamped.empty())
    diag.warn(name + ": Kd clamped to --max-reflectance " + num(options.max_reflectance) +
              " in material(s) " + list_names(clamped));
  if (!unused.transparency.empty())
    diag.warn(name + ": d/Tr < 1 of material(s) " + list_names(unused.transparency) +
              " ignored: transparency without refraction is not modelled (illum 7 refracts)");
  auto add_default = [&](const std::string& mat_name) {
    scene.materials.push_back({mat_name, options.default_reflectance, Eigen::Vector3d::Zero()});
    return static_cast<std::int32_t>(scene.materials.size() - 1);
  };
  for (const auto& use : obj.materials) {
    auto it = by_name.find(use.name);
    if (it != by_name.end()) {
      out.of_use.push_back(it->second);
      out.undefined.push_back(false);
      if (lossless.count(use.name)) out.lossless.insert(use.name);
      continue;
    }
    out.undefined.push_back(true);
    if (use.name.empty()) {
      if (out.none < 0) out.none = add_default("default");
      out.of_use.push_back(out.none);
      continue;
    }
    out.of_use.push_back(add_default(use.name));
  }
  const bool bare = std::any_of(obj.faces.begin(), obj.faces.end(),
                                [](const ObjFace& f) { return f.material < 0; });
  if (bare && out.none < 0) out.none = add_default("default");
  return out;
}

// --vertex-colors-as-reflectance: checks the file's colours and brings them to [0, 1].
// Components above 1, all whole numbers up to 255, are the common 0..255 convention: every
// colour of the file is divided by 255, with a warning (--strict refuses). Anything else
// outside [0, 1] is refused. Without the option the colours are dropped (and counted as
// skipped).
void prepare_colors(ObjData& obj, const LoadOptions& options, const std::string& name,
                    Diagnostics& diag) {
  ObjColors& c = obj.colors;
  if (!options.vertex_colors_as_reflectance) {
    c.of_vertex.clear();
    return;
  }
  if (c.of_vertex.empty()) {
    diag.warn(name + ": --vertex-colors-as-reflectance: no vertex has a colour (v x y z r g b): "
              "every face keeps its material's Kd");
    return;
  }
  obj.skipped.erase("vertex colours");  // used, not skipped
  if (c.min < 0.0)
    throw SceneError(where(name, c.min_line) + ": vertex colour component " + num(c.min) +
                     " is negative: a reflectance lies in [0, 1]");
  if (c.max <= 1.0) return;
  const std::string at = where(name, c.max_line) + ": vertex colour component " + num(c.max);
  if (c.max > 255.0 || !c.all_integers)
    throw SceneError(at + " is above 1: a reflectance lies in [0, 1] (colours in 0..255 are "
                     "read when all are whole numbers); rescale the colours");
  diag.defaulted(at + " is above 1: a reflectance lies in [0, 1]; rescale the colours",
                 at + " is above 1: the file's colours are read as 0..255 and divided by 255");
  for (auto& v : c.of_vertex) v /= 255.0;
}

// Mean colour of a face's corners; none unless every corner has a colour.
std::optional<Eigen::Vector3d> corner_mean(const ObjColors& colors,
                                           const std::vector<std::int32_t>& corners) {
  if (colors.of_vertex.empty()) return std::nullopt;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto v : corners) {
    if (std::isnan(colors.of_vertex[v][0])) return std::nullopt;
    sum += colors.of_vertex[v];
  }
  return sum / static_cast<double>(corners.size());
}

// The polygon of a face with repeated corners collapsed (same index or position as the
// previous one, or the last equal to the first): they add nothing but zero-length edges.
std::vector<Eigen::Vector3d> collapse_corners(const std::vector<Eigen::Vector3d>& verts,
                                              Face& face, const std::vector<std::int32_t>& in) {
  std::vector<Eigen::Vector3d> poly;
  for (const std::int32_t vi : in) {
    if (!poly.empty() && (vi == face.vertices.back() || verts[vi] == poly.back())) continue;
    face.vertices.push_back(vi);
    poly.push_back(verts[vi]);
  }
  while (poly.size() > 1 && poly.back() == poly.front()) {
    poly.pop_back();
    face.vertices.pop_back();
  }
  return poly;
}

// Faces (collapsed, degenerate ones dropped, non-planar ones split) and their surfaces:
// one per (group, material), named `group`, or `group/material` when the group's faces
// use several materials. Returns, per usemtl index + 1 (0 = none), the surfaces using it.
std::map<std::int32_t, std::set<std::int32_t>> build_faces(const ObjData& obj,
                                                           const Materials& mats,
                                                           const std::string& name,
                                                           Diagnostics& diag, LoadReport& report,
                                                           Scene& scene) {
  auto material_of = [&](const ObjFace& f) { return f.material < 0 ? mats.none : mats.of_use[f.material]; };
  std::vector<std::set<std::int32_t>> group_materials(obj.groups.size());
  for (const auto& f : obj.faces) group_materials[f.group].insert(material_of(f));
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> surface_of;
  std::map<std::int32_t, std::set<std::int32_t>> surfaces_of_use;
  struct {
    int first_line = 0, worst_line = 0;
    double worst = 0.0, worst_relative = 0.0;
  } nonplanar;
  for (const auto& of : obj.faces) {
    Face face;
    face.line = of.line;
    const std::vector<Eigen::Vector3d> poly = collapse_corners(scene.vertices, face, of.vertices);
    const std::set<std::int32_t> distinct(face.vertices.begin(), face.vertices.end());
    const double extent = polygon_extent(poly);
    if (distinct.size() < 3 || is_degenerate_polygon(poly)) {
      ++report.degenerate_faces_dropped;
      log_debug(where(name, of.line) + ": zero-area face dropped");
      continue;
    }
    face.rho = corner_mean(obj.colors, face.vertices);
    const std::int32_t mat = material_of(of);
    auto it = surface_of.find({of.group, mat});
    if (it == surface_of.end()) {
      const std::string& group = obj.groups[of.group];
      const std::string sname =
          group_materials[of.group].size() > 1 ? group + "/" + scene.materials[mat].name : group;
      it = surface_of.emplace(std::make_pair(of.group, mat),
                              static_cast<std::int32_t>(scene.surfaces.size())).first;
      scene.surfaces.push_back({sname, mat});
    }
    face.surface = it->second;
    surfaces_of_use[of.material + 1].insert(face.surface);
    const double off = planarity_deviation(poly);
    if (off <= kPlanarityRelTol * extent) {
      scene.faces.push_back(std::move(face));
      continue;
    }
    if (poly.size() > kMaxSplitCorners)
      throw SceneError(where(name, of.line) + ": non-planar polygon with " +
                       std::to_string(poly.size()) + " corners (more than " +
                       std::to_string(kMaxSplitCorners) + " cannot be split into triangles)");
    // One warning for them all after the loop (a CAD export has thousands): count, first
    // line, and the worst one's deviation relative to its size.
    if (report.nonplanar_faces_split++ == 0) nonplanar.first_line = of.line;
    if (off / extent > nonplanar.worst_relative) {
      nonplanar.worst_relative = off / extent;
      nonplanar.worst = off;
      nonplanar.worst_line = of.line;
    }
    log_debug(where(name, of.line) + ": non-planar polygon (off its plane by " + num(off) +
              ") split into triangles");
    for (const auto& t : triangulate(poly)) {
      Face tri = face;
      tri.vertices = {face.vertices[t[0]], face.vertices[t[1]], face.vertices[t[2]]};
      scene.faces.push_back(tri);
    }
  }
  if (report.nonplanar_faces_split > 0) {
    const int n = report.nonplanar_faces_split;
    const std::string off = "off its plane by " + num(nonplanar.worst) + ", " +
                            num(100.0 * nonplanar.worst_relative) + " % of its size";
    diag.warn(where(name, nonplanar.first_line) + ": " +
              (n == 1 ? "non-planar polygon (" + off + ") split into triangles"
                      : std::to_string(n) +
                            " non-planar polygons (the first here) split into triangles; the "
                            "worst (line " +
                            std::to_string(nonplanar.worst_line) + ") is " + off));
  }
  return surfaces_of_use;
}

// One warning per cause of a default material, naming the surfaces it affects; --strict
// refuses instead (with the messages lambert gave before defaults existed).
void report_default_materials(const ObjData& obj, const Materials& mats,
                              const std::map<std::int32_t, std::set<std::int32_t>>& users,
                              const std::string& name, const LoadOptions& options,
                              Diagnostics& diag, const Scene& scene) {
  auto surfaces = [&](std::int32_t use) {
    std::set<std::string> names;
    auto it = users.find(use + 1);
    if (it != users.end())
      for (auto s : it->second) names.insert(scene.surfaces[s].name);
    return names;
  };
  const std::string deflt = "the default material (rho " + rgb(options.default_reflectance) +
                            ", no emission; --default-reflectance R,G,B)";
  for (size_t u = 0; u < obj.materials.size(); ++u) {
    if (!mats.undefined[u]) continue;
    const ObjMaterialUse& use = obj.materials[u];
    const auto names = surfaces(static_cast<std::int32_t>(u));
    const std::string at = where(name, use.line);
    const std::string what = use.name.empty()
                                 ? at + ": usemtl without a material name"
                                 : at + ": material '" + use.name + "' is not defined" +
                                       (obj.mtllibs.empty() ? " (no mtllib)" : " in the material library");
    if (diag.strict()) throw SceneError(what);
    if (!names.empty()) diag.warn(what + ": surface(s) " + list_names(names) + " use " + deflt);
  }
  const auto none = surfaces(-1);
  if (none.empty()) return;
  int first = 0;
  for (const auto& f : obj.faces) {
    if (f.material < 0) {
      first = f.line;
      break;
    }
  }
  const std::string at = where(name, first);
  diag.defaulted(at + ": face has no material (no usemtl before it)",
                 at + ": faces without usemtl" + (obj.mtllibs.empty() ? " (and no mtllib)" : "") +
                     ": surface(s) " + list_names(none) + " use " + deflt);
}

// Faces coloured on some corners only (they keep Kd), --max-reflectance on colours, and
// lossless colours (refused with --strict). Returns the surfaces with a lossless face colour.
std::set<std::string> report_face_colors(const ObjColors& colors, const LoadOptions& options,
                                         const std::string& name, Diagnostics& diag,
                                         Scene& scene) {
  std::set<std::string> partial, clamped, lossless;
  int first_partial = 0;
  for (Face& f : scene.faces) {
    const std::string& surface = scene.surfaces[f.surface].name;
    if (!f.rho) {
      const bool some = !colors.of_vertex.empty() &&
          std::any_of(f.vertices.begin(), f.vertices.end(),
                      [&](std::int32_t v) { return !std::isnan(colors.of_vertex[v][0]); });
      if (some && partial.insert(surface).second && first_partial == 0) first_partial = f.line;
      continue;
    }
    if (options.max_reflectance > 0 && f.rho->maxCoeff() > options.max_reflectance) {
      *f.rho = f.rho->cwiseMin(options.max_reflectance);
      clamped.insert(surface);
    }
    if (f.rho->maxCoeff() < 1.0) continue;
    if (options.strict)
      throw SceneError(where(name, f.line) + ": face colour (mean of its corners) " + rgb(*f.rho) +
                       " must lie in [0, 1) in every channel with --strict");
    lossless.insert(surface);
  }
  if (!partial.empty())
    diag.warn(where(name, first_partial) + ": faces with colours on only some corners keep "
              "their material's Kd: surface(s) " + list_names(partial));
  if (!clamped.empty())
    diag.warn(name + ": vertex-colour reflectance clamped to --max-reflectance " +
              num(options.max_reflectance) + " on surface(s) " + list_names(clamped));
  return lossless;
}

// Kd = 1 (or a face colour of 1) is lossless: accepted, but the system is singular when a
// closed set of such surfaces absorbs nothing, which the loader (without form factors)
// cannot see; the commands check it once F is known (find_closed_lossless).
void report_lossless(const Materials& mats, const std::set<std::string>& colored,
                     const std::string& name, Diagnostics& diag, const Scene& scene) {
  if (mats.lossless.empty() && colored.empty()) return;
  bool closed_risk = false;  // some channel in which every face is lossless
  for (int c = 0; c < 3; ++c) {
    bool every = true;
    for (const auto& f : scene.faces)
      every = every && (f.rho ? *f.rho : scene.material_of(f.surface).rho)[c] == 1.0;
    closed_risk = closed_risk || every;
  }
  const std::string what =
      (mats.lossless.empty() ? "" : "material(s) " + list_names(mats.lossless)) +
      (mats.lossless.empty() || colored.empty() ? "" : " and ") +
      (colored.empty() ? "" : "vertex colours of surface(s) " + list_names(colored));
  diag.warn(name + ": " + what +
            " have reflectance 1 in some channel (lossless): the radiosity system is singular "
            "if such surfaces enclose a space where nothing absorbs" +
            (closed_risk ? " (here every surface is lossless in one channel)" : "") +
            ", which is refused once form factors are known; --max-reflectance 0.99 clamps");
}

// With specular surfaces, a scene where some channel is reflected or transmitted in full
// everywhere (Kd + Ks = 1 on mirrors, Tf = 1 on dielectrics, Kd = 1 elsewhere) never absorbs
// that channel: refused (light would bounce forever; a purely diffuse such scene keeps the
// warning above and the check once F is known).
void refuse_lossless_specular(const Scene& scene, const std::string& name) {
  const bool specular = std::any_of(scene.faces.begin(), scene.faces.end(), [&](const Face& f) {
    return scene.material_of(f.surface).specular.any();
  });
  if (!specular) return;
  static const char* const kChannel[] = {"red", "green", "blue"};
  for (int c = 0; c < 3; ++c) {
    bool every = true;
    for (const auto& f : scene.faces) {
      const Material& m = scene.material_of(f.surface);
      const double kept = m.specular.dielectric
                              ? m.specular.transmission[c]
                              : (f.rho ? *f.rho : m.rho)[c] + m.specular.reflectance[c];
      every = every && kept >= 1.0;
    }
    if (every)
      throw SceneError(name + ": no surface absorbs " + kChannel[c] + " light (every material "
                       "reflects or transmits all of it: Kd + Ks = 1, or Tf = 1 on dielectrics): "
                       "light would never be absorbed and the radiosity has no solution");
  }
}

// Face colours (--vertex-colors-as-reflectance) replace Kd, so they obey the rules Kd does
// on specular materials: 0 on a dielectric, colour + Ks <= 1 on a mirror.
void check_specular_face_colors(const Scene& scene, const std::string& name) {
  for (const auto& f : scene.faces) {
    if (!f.rho) continue;
    const Material& m = scene.material_of(f.surface);
    if (m.specular.dielectric && f.rho->maxCoeff() > 0.0)
      throw SceneError(where(name, f.line) + ": face colour " + rgb(*f.rho) + " on dielectric '" +
                       m.name + "': a dielectric's diffuse reflectance must be 0");
    if (!m.specular.dielectric && (*f.rho + m.specular.reflectance).maxCoeff() > 1.0)
      throw SceneError(where(name, f.line) + ": face colour " + rgb(*f.rho) + " + Ks " +
                       rgb(m.specular.reflectance) + " of mirror '" + m.name +
                       "' exceeds 1 in some channel");
  }
}

// What was skipped, in one warning.
void report_skipped(const ObjData& obj, const std::string& name, Diagnostics& diag,
                    LoadReport& report) {
  if (obj.skipped.empty()) return;
  std::string list;
  for (const auto& [what, s] : obj.skipped) {
    report.skipped_statements += s.count;
    list += (list.empty() ? "" : ", ") + std::to_string(s.count) + " " + what + " (first at line " +
            std::to_string(s.first_line) + ")";
  }
  diag.warn(name + ": skipped what radiosity does not use: " + list);
}

// Sorted corner positions of a face: equal for two faces covering the same polygon.
std::vector<std::array<double, 3>> corner_key(const Scene& scene, const Face& f) {
  std::vector<std::array<double, 3>> key;
  for (auto v : f.vertices) key.push_back({scene.vertices[v].x(), scene.vertices[v].y(), scene.vertices[v].z()});
  std::sort(key.begin(), key.end());
  return key;
}

std::uint64_t hash_key(const std::vector<std::array<double, 3>>& key) {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the coordinates' bits
  for (const auto& p : key) {
    for (double x : p) {
      std::uint64_t bits;
      std::memcpy(&bits, &x, sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
    }
  }
  return h;
}

}  // namespace

// Faces with exactly the corners of an earlier face (a second copy of the floor) count
// their area twice and push row sums of F above 1: one warning per pair of surfaces.
// Faces are bucketed by a hash of their sorted corners and compared exactly.
std::vector<std::string> coincident_face_warnings(const Scene& scene, const std::string& name,
                                                  int& coincident_faces) {
  std::vector<std::string> warnings;
  std::unordered_multimap<std::uint64_t, size_t> seen;
  seen.reserve(scene.faces.size());
  std::map<std::pair<std::int32_t, std::int32_t>, std::pair<size_t, int>> pairs;  // -> (f, count)
  std::vector<std::pair<size_t, size_t>> examples;
  for (size_t f = 0; f < scene.faces.size(); ++f) {
    const auto key = corner_key(scene, scene.faces[f]);
    const std::uint64_t h = hash_key(key);
    auto [lo, hi] = seen.equal_range(h);
    auto it = std::find_if(lo, hi, [&](const auto& e) { return corner_key(scene, scene.faces[e.second]) == key; });
    if (it == hi) {
      seen.emplace(h, f);
      continue;
    }
    ++coincident_faces;
    const Face& a = scene.faces[it->second];
    const Face& b = scene.faces[f];
    auto [p, fresh] = pairs.emplace(std::minmax(a.surface, b.surface), std::make_pair(f, 0));
    if (fresh) examples.emplace_back(it->second, f);
    ++p->second.second;
  }
  for (const auto& [fa, fb] : examples) {
    const Face& a = scene.faces[fa];
    const Face& b = scene.faces[fb];
    const int count = pairs[std::minmax(a.surface, b.surface)].second;
    // Binary STL facets have no line: name the pair of surfaces only.
    const std::string first =
        a.line > 0 ? "the face at line " + std::to_string(a.line) : "an earlier face";
    warnings.push_back(where(name, b.line) + ": face coincides with " + first + " (surfaces '" +
                       scene.surfaces[a.surface].name + "' and '" + scene.surfaces[b.surface].name +
                       "', " + std::to_string(count) +
                       " coincident face(s)): its area counts twice");
  }
  return warnings;
}

void apply_emit(const std::vector<EmitRule>& rules, const std::string& name, Scene& scene) {
  auto matches = [](const std::string& pattern, const std::string& s) {
    return fnmatch(pattern.c_str(), s.c_str(), 0) == 0;
  };
  for (const auto& rule : rules) {
    if (!rule.emission.allFinite() || rule.emission.minCoeff() < 0.0)
      throw UsageError("--emit " + rule.pattern + ": emission must be finite and >= 0");
    std::vector<bool> hit(scene.surfaces.size());
    bool any = false;
    for (size_t s = 0; s < scene.surfaces.size(); ++s) {
      hit[s] = matches(rule.pattern, scene.surfaces[s].name) ||
               matches(rule.pattern, scene.material_of(static_cast<std::int32_t>(s)).name);
      any = any || hit[s];
    }
    if (!any)
      throw UsageError("--emit '" + rule.pattern + "': no surface or material of " + name +
                       " matches (lambert info lists the names)");
    std::vector<bool> shared(scene.materials.size());  // also used by an unmatched surface
    for (size_t s = 0; s < scene.surfaces.size(); ++s)
      if (!hit[s]) shared[scene.surfaces[s].material] = true;
    for (size_t s = 0; s < scene.surfaces.size(); ++s) {
      if (!hit[s]) continue;
      Surface& surf = scene.surfaces[s];
      if (shared[surf.material]) {
        Material copy = scene.materials[surf.material];
        copy.name += "@" + surf.name;
        surf.material = static_cast<std::int32_t>(scene.materials.size());
        scene.materials.push_back(copy);
      }
      scene.materials[surf.material].emission = rule.emission;
    }
  }
}

std::string builtin_cornell_box_path() {
  if (const char* dir = std::getenv("LAMBERT_DATA_DIR"))
    return (fs::path(dir) / "cornell_box" / "cornell_box.obj").string();
  return (fs::path(LAMBERT_DATA_DIR) / "cornell_box" / "cornell_box.obj").string();
}

Scene load_obj_stream(std::istream& in, const std::string& name, const MtlOpener& open_mtl,
                      LoadReport* report_out, const LoadOptions& options) {
  LoadReport report;
  Diagnostics diag(options.strict, report);
  ObjData obj = parse_obj(in, name);
  prepare_colors(obj, options, name, diag);
  const std::vector<MtlMaterial> defs = read_libraries(obj, name, open_mtl, diag);
  Scene scene;
  scene.source = name;
  const Materials mats = build_materials(obj, defs, options, name, diag, scene);
  scene.vertices = std::move(obj.vertices);
  const auto users = build_faces(obj, mats, name, diag, report, scene);
  report_default_materials(obj, mats, users, name, options, diag, scene);
  const auto colored_lossless = report_face_colors(obj.colors, options, name, diag, scene);
  report_lossless(mats, colored_lossless, name, diag, scene);
  check_specular_face_colors(scene, name);
  refuse_lossless_specular(scene, name);
  report_skipped(obj, name, diag, report);
  if (report.degenerate_faces_dropped > 0)
    diag.warn(name + ": " + std::to_string(report.degenerate_faces_dropped) + " zero-area face(s) dropped");
  if (scene.faces.empty()) throw SceneError(name + ": empty scene: no faces with positive area");
  const auto [lo, hi] = scene.bounds();
  if ((hi - lo).norm() < kMinSceneExtent)
    throw SceneError(name + ": scene extent " + num((hi - lo).norm()) +
                     " is below 1e-50, where form factors underflow: rescale the scene");
  report.default_material_used =
      std::any_of(mats.undefined.begin(), mats.undefined.end(), [](bool u) { return u; }) ||
      std::any_of(obj.faces.begin(), obj.faces.end(),
                  [](const ObjFace& f) { return f.material < 0; });
  if (options.split_angle >= 0.0) split_surfaces_at_feature_edges(scene, options.split_angle, name);
  for (const std::string& w : coincident_face_warnings(scene, name, report.coincident_faces))
    diag.warn(w);
  apply_emit(options.emit, name, scene);
  for (const auto& s : scene.surfaces) report.has_emitter = report.has_emitter || scene.materials[s.material].emits();
  if (!report.has_emitter && options.warn_without_emitter)
    diag.warn(name + ": no emitter (no material with Ke > 0): the radiosity is zero; add one with "
              "--emit SURFACE_OR_MATERIAL=R,G,B (lambert info lists the names)");
  scene.camera = three_quarter_camera(lo, hi, 1);  // OBJ: y up (a .camera sidecar wins)
  if (report_out) *report_out = std::move(report);
  return scene;
}

Scene load_obj(const std::string& path, LoadReport* report, const LoadOptions& options) {
  std::ifstream in = open_or_throw(path);
  const fs::path base = fs::path(path).parent_path();
  std::vector<std::string> files{path};
  // An mtllib names a file next to the OBJ; exporters also write absolute or Windows paths
  // of the author's machine, so the bare file name next to the OBJ is tried as well.
  const MtlOpener open_mtl = [&](const std::string& lib) -> MtlFile {
    std::string bare = lib;
    std::replace(bare.begin(), bare.end(), '\\', '/');
    bare = fs::path(bare).filename().string();
    for (const fs::path& p : {base / lib, base / bare}) {
      std::error_code ec;
      if (bare.empty() || !fs::exists(p, ec) || fs::is_directory(p, ec)) continue;
      auto f = std::make_unique<std::ifstream>(p, std::ios::binary);
      if (!*f) throw IoError(p.string() + ": cannot open: " + std::strerror(errno));
      files.push_back(p.string());
      return {std::move(f), p.string()};
    }
    return {};
  };
  Scene scene = load_obj_stream(in, path, open_mtl, report, options);
  const fs::path camera_path = fs::path(path).replace_extension(".camera");
  std::error_code ec;
  if (fs::exists(camera_path, ec)) {
    scene.camera = read_camera_file(camera_path.string());
    files.push_back(camera_path.string());
  }
  scene.files = std::move(files);
  return scene;
}

}  // namespace lambert
