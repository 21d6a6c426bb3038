#include "io/stl_loader.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include "core/error.hpp"
#include "core/log.hpp"
#include "geometry/polygon.hpp"
#include "io/camera_file.hpp"
#include "io/line_reader.hpp"
#include "io/obj_loader.hpp"
#include "io/obj_parser.hpp"
#include "io/strict_number.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kHeaderBytes = 84;  // 80-byte header + uint32 facet count
constexpr std::uint64_t kFacetBytes = 50;   // normal, 3 corners (12 float32) + uint16 attribute

using Corners = std::array<Eigen::Vector3d, 3>;

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

// True when the text starts, after blanks and line breaks, with the keyword `solid`.
bool starts_with_solid(const std::string& bytes) {
  size_t i = 0;
  if (bytes.compare(0, 3, "\xEF\xBB\xBF") == 0) i = 3;  // UTF-8 byte-order mark
  while (i < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[i]))) ++i;
  if (!iequals(std::string_view(bytes).substr(i, 5), "solid")) return false;
  return i + 5 == bytes.size() || std::isspace(static_cast<unsigned char>(bytes[i + 5]));
}

std::uint32_t le_u32(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return std::uint32_t{b[0]} | std::uint32_t{b[1]} << 8 | std::uint32_t{b[2]} << 16 |
         std::uint32_t{b[3]} << 24;
}

float le_f32(const char* p) {
  const std::uint32_t bits = le_u32(p);
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

// Builds the scene: vertices shared by exact position, faces with their surface, the checks
// every facet gets (zero area, stored normal against the winding).
class SceneBuilder {
 public:
  SceneBuilder(const std::string& name, LoadReport& report) : name_(name), report_(report) {
    scene_.source = name;
  }

  // Adds a facet to `surface` (-1: assigned later) from source line `line` (0: binary).
  void add_facet(const Corners& c, const Eigen::Vector3d& stored_normal, std::int32_t surface,
                 int line) {
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

  std::int32_t surface(const std::string& surface_name) {
    auto [it, added] =
        surface_of_.emplace(surface_name, static_cast<std::int32_t>(scene_.surfaces.size()));
    if (added) scene_.surfaces.push_back({surface_name, 0});
    return it->second;
  }

  Scene& scene() { return scene_; }

  // Warnings, the default material, the emit rules, the camera; refuses an empty scene.
  Scene finish(const LoadOptions& options) {
    if (report_.degenerate_faces_dropped > 0)
      warn(name_ + ": " + std::to_string(report_.degenerate_faces_dropped) +
           " zero-area facet(s) dropped");
    if (flipped_ > 0)
      warn(name_ + ": " + std::to_string(flipped_) +
           " facet(s) store a normal opposite to their vertex order; the vertex order "
           "(counter-clockwise about the front) is used");
    if (scene_.faces.empty())
      throw SceneError(name_ + ": empty scene: no facets with positive area");
    for (const std::string& w : coincident_face_warnings(scene_, name_, report_.coincident_faces))
      warn(w);
    scene_.materials.push_back({"default", options.default_reflectance, Eigen::Vector3d::Zero()});
    report_.default_material_used = true;
    apply_emit(options.emit, name_, scene_);
    for (const auto& s : scene_.surfaces)
      report_.has_emitter = report_.has_emitter || scene_.materials[s.material].emits();
    const auto [lo, hi] = scene_.bounds();
    // The OBJ loader's floor (io/obj_loader.cpp): distances^4 must stay normal doubles.
    if ((hi - lo).norm() < 1e-50)
      throw SceneError(name_ +
                       ": scene extent below 1e-50, where form factors underflow: "
                       "rescale the scene");
    scene_.camera = three_quarter_camera(lo, hi, 2);  // CAD: z up
    return std::move(scene_);
  }

 private:
  std::int32_t vertex(const Eigen::Vector3d& p) {
    auto [it, added] = index_.emplace(key(p), static_cast<std::int32_t>(scene_.vertices.size()));
    if (added) scene_.vertices.push_back(p);
    return it->second;
  }
  static std::string key(const Eigen::Vector3d& p) {
    Eigen::Vector3d q = p + Eigen::Vector3d::Zero();  // -0 and +0 are one position
    return std::string(reinterpret_cast<const char*>(q.data()), sizeof(double) * 3);
  }
  void warn(const std::string& msg) {
    log_warn(msg);
    report_.warnings.push_back(msg);
  }

  std::string name_;
  LoadReport& report_;
  Scene scene_;
  std::unordered_map<std::string, std::int32_t> index_;
  std::map<std::string, std::int32_t> surface_of_;
  int flipped_ = 0;
};

std::string stem_of(const std::string& name) {
  const std::string stem = fs::path(name).stem().string();
  return stem.empty() ? "stl" : stem;
}

// ASCII: solid NAME / facet normal N / outer loop / vertex x3 / endloop / endfacet / endsolid.
class AsciiReader {
 public:
  AsciiReader(std::istream& in, const std::string& name, SceneBuilder& out)
      : lines_(in, name), name_(name), out_(out) {}

  void read() {
    std::vector<std::pair<std::string, int>> solids;  // name, line (for unnamed blocks)
    while (next_line()) {
      expect(0, "solid");
      std::string solid = join_tokens(tok_, 1);
      const int at = lines_.line_number();
      solids.emplace_back(solid, at);
      read_solid(static_cast<int>(solids.size()));
    }
    if (solids.empty()) throw SceneError(name_ + ": no 'solid' in the file");
  }

 private:
  bool next_line() {
    std::string_view line;
    while (lines_.next(line)) {
      split_fields(line, tok_);
      if (!tok_.empty()) return true;
    }
    return false;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError(lines_.where() + ": " + what);
  }
  std::string got() const {
    return tok_.empty() ? "an empty line" : "'" + join_tokens(tok_, 0) + "'";
  }
  void expect(size_t k, const char* word) const {
    if (tok_.size() <= k || !iequals(tok_[k], word))
      fail(std::string("expected '") + word + "', got " + got());
  }
  void require_line(const char* what) {
    if (!next_line())
      throw SceneError(name_ + ": end of file inside a solid (" + what + " missing): truncated?");
  }
  Eigen::Vector3d numbers(size_t first, const char* what) const {
    if (tok_.size() != first + 3) fail(std::string("expected '") + what + " X Y Z', got " + got());
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) {
      const std::string why = parse_finite(tok_[first + k], v[k]);
      if (!why.empty()) fail("'" + std::string(tok_[first + k]) + "': " + why);
      // The OBJ loader's limit (io/obj_parser.hpp): distances^4 must stay finite.
      if (std::string(what) == "vertex" && std::abs(v[k]) > kMaxObjCoordinate)
        fail("'" + std::string(tok_[first + k]) + "': coordinate beyond +-1e50: rescale the scene");
    }
    return v;
  }
  void read_solid(int block) {
    const std::string solid = join_tokens(tok_, 1);
    std::int32_t surface = -1;
    for (;;) {
      require_line("endsolid");
      if (iequals(tok_[0], "endsolid")) break;
      expect(0, "facet");
      expect(1, "normal");
      const int line = lines_.line_number();
      const Eigen::Vector3d normal = numbers(2, "facet normal");
      require_line("outer loop");
      expect(0, "outer");
      expect(1, "loop");
      if (tok_.size() != 2) fail("expected 'outer loop', got " + got());
      Corners c;
      for (auto& p : c) {
        require_line("vertex");
        expect(0, "vertex");
        p = numbers(1, "vertex");
      }
      require_line("endloop");
      if (iequals(tok_[0], "vertex")) fail("a facet has 3 vertices, this one more");
      expect(0, "endloop");
      require_line("endfacet");
      expect(0, "endfacet");
      if (surface < 0) surface = out_.surface(surface_name(solid, block));
      out_.add_facet(c, normal, surface, line);
    }
  }
  std::string surface_name(const std::string& solid, int block) const {
    if (!solid.empty()) return solid;
    return stem_of(name_) + (block > 1 ? "_" + std::to_string(block) : "");
  }

  LineReader lines_;
  std::string name_;
  SceneBuilder& out_;
  std::vector<std::string_view> tok_;
};

// Union-find root with path halving.
std::int32_t root(std::vector<std::int32_t>& parent, std::int32_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

// Binary: one surface per connected component (shared corner positions), in facet order.
void read_binary(const std::string& bytes, const std::string& name, SceneBuilder& out) {
  if (bytes.size() < kHeaderBytes)
    throw SceneError(name + ": binary STL of " + std::to_string(bytes.size()) +
                     " bytes is shorter than its 84-byte header: truncated");
  const std::uint64_t count = le_u32(bytes.data() + 80);
  const std::uint64_t expected = kHeaderBytes + kFacetBytes * count;
  const std::uint64_t size = bytes.size();
  if (size < expected)
    throw SceneError(name + ": facet " + std::to_string((size - kHeaderBytes) / kFacetBytes + 1) +
                     ": binary STL truncated: the header declares " + std::to_string(count) +
                     " facets (" + std::to_string(expected) + " bytes), the file has " +
                     std::to_string(size) + " bytes");
  if (size > expected)
    throw SceneError(name + ": binary STL facet count " + std::to_string(count) +
                     " does not match the size: " + std::to_string(size) + " bytes hold " +
                     std::to_string((size - kHeaderBytes) / kFacetBytes) + " facets and " +
                     std::to_string((size - kHeaderBytes) % kFacetBytes) + " more bytes");
  for (std::uint64_t f = 0; f < count; ++f) {
    const char* p = bytes.data() + kHeaderBytes + kFacetBytes * f;
    std::array<double, 12> x;
    for (int k = 0; k < 12; ++k) {
      x[k] = le_f32(p + 4 * k);
      if (!std::isfinite(x[k]))
        throw SceneError(name + ": facet " + std::to_string(f + 1) + ": " +
                         (k < 3 ? "normal" : "vertex " + std::to_string(k / 3)) +
                         " has a non-finite coordinate");
    }
    const Corners c{Eigen::Vector3d(x[3], x[4], x[5]), Eigen::Vector3d(x[6], x[7], x[8]),
                    Eigen::Vector3d(x[9], x[10], x[11])};
    out.add_facet(c, Eigen::Vector3d(x[0], x[1], x[2]), -1, 0);
  }
  Scene& scene = out.scene();
  std::vector<std::int32_t> parent(scene.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const Face& f : scene.faces)
    for (size_t k = 1; k < f.vertices.size(); ++k)
      parent[root(parent, f.vertices[k])] = root(parent, f.vertices[0]);
  std::map<std::int32_t, std::int32_t> component;  // root -> number, in first-facet order
  for (const Face& f : scene.faces)
    component.emplace(root(parent, f.vertices[0]), component.size());
  const std::string stem = stem_of(name);
  std::vector<std::int32_t> surface(component.size());
  // Surfaces are created in first-facet order so that surface k is component k.
  std::vector<std::int32_t> order(component.size());
  for (const auto& [r, k] : component) order[k] = r;
  for (size_t k = 0; k < order.size(); ++k)
    surface[k] = out.surface(order.size() == 1 ? stem : stem + "_" + std::to_string(k + 1));
  for (Face& f : scene.faces) f.surface = surface[component[root(parent, f.vertices[0])]];
}

std::string read_all(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path + ": cannot open: file not found");
  if (fs::is_directory(path, ec)) throw IoError(path + ": cannot open: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open: " + std::strerror(errno));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(path + ": read error");
  return bytes;
}

}  // namespace

bool looks_like_stl(const std::string& head, std::uint64_t size) {
  if (size >= kHeaderBytes && head.size() >= kHeaderBytes &&
      size == kHeaderBytes + kFacetBytes * std::uint64_t{le_u32(head.data() + 80)})
    return true;
  if (starts_with_solid(head)) return true;
  return head.find('\0') < kHeaderBytes;
}

StlKind stl_kind(const std::string& bytes) {
  if (bytes.size() >= kHeaderBytes &&
      bytes.size() == kHeaderBytes + kFacetBytes * std::uint64_t{le_u32(bytes.data() + 80)})
    return StlKind::Binary;
  return starts_with_solid(bytes) && bytes.find('\0') == std::string::npos ? StlKind::Ascii
                                                                           : StlKind::Binary;
}

Scene load_stl_bytes(const std::string& bytes, const std::string& name, LoadReport* report_out,
                     const LoadOptions& options) {
  LoadReport report;
  SceneBuilder out(name, report);
  if (stl_kind(bytes) == StlKind::Binary) {
    read_binary(bytes, name, out);
  } else {
    std::istringstream in(bytes);
    AsciiReader(in, name, out).read();
  }
  Scene scene = out.finish(options);
  if (report_out) *report_out = std::move(report);
  return scene;
}

Scene load_stl(const std::string& path, LoadReport* report, const LoadOptions& options) {
  Scene scene = load_stl_bytes(read_all(path), path, report, options);
  scene.files = {path};
  const fs::path camera_path = fs::path(path).replace_extension(".camera");
  std::error_code ec;
  if (fs::exists(camera_path, ec)) {
    scene.camera = read_camera_file(camera_path.string());
    scene.files.push_back(camera_path.string());
  }
  return scene;
}

Scene load_scene_path(const std::string& path, LoadReport* report, const LoadOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (in) {
    std::string head(kHeaderBytes, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<size_t>(in.gcount()));
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (!ec && looks_like_stl(head, size)) return load_stl(path, report, options);
  }
  return load_obj(path, report, options);  // also reports a missing or unreadable file
}

}  // namespace lambert
