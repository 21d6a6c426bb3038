#include "io/ply_loader.hpp"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "io/camera_file.hpp"
#include "io/soup_builder.hpp"
#include "io/strict_number.hpp"

namespace lambert {
namespace {

namespace fs = std::filesystem;

enum class Format { Ascii, Little, Big };

// A property's storage type and its size in bytes.
struct Type {
  int bytes = 0;
  bool is_float = false, is_signed = false;
};

std::optional<Type> type_named(std::string_view t) {
  if (t == "char" || t == "int8") return Type{1, false, true};
  if (t == "uchar" || t == "uint8") return Type{1, false, false};
  if (t == "short" || t == "int16") return Type{2, false, true};
  if (t == "ushort" || t == "uint16") return Type{2, false, false};
  if (t == "int" || t == "int32") return Type{4, false, true};
  if (t == "uint" || t == "uint32") return Type{4, false, false};
  if (t == "float" || t == "float32") return Type{4, true, true};
  if (t == "double" || t == "float64") return Type{8, true, true};
  return std::nullopt;
}

struct Property {
  std::string name;
  Type type;  // the value's (a list's items')
  bool list = false;
  Type count;  // a list's count type
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  int line = 0;  // header line that declares it
};

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

// Reads the body: binary values at `pos`, or ASCII tokens.
class Body {
 public:
  Body(const std::string& bytes, size_t pos, Format format, std::string name)
      : bytes_(bytes), pos_(pos), format_(format), name_(std::move(name)) {}

  // The next value of type t; `what` names it in errors ("vertex 12").
  double value(const Type& t, const std::string& what) {
    if (format_ == Format::Ascii) return ascii(t, what);
    if (pos_ + t.bytes > bytes_.size())
      throw SceneError(name_ + ": " + what + ": the file ends inside it (truncated)");
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + pos_, t.bytes);
    pos_ += t.bytes;
    const bool swap = format_ == Format::Big;
    if (swap)
      for (int k = 0; k < t.bytes / 2; ++k) std::swap(b[k], b[t.bytes - 1 - k]);
    if (t.is_float) {
      if (t.bytes == 4) {
        float f;
        std::memcpy(&f, b, 4);
        return f;
      }
      double d;
      std::memcpy(&d, b, 8);
      return d;
    }
    std::uint64_t u = 0;
    for (int k = t.bytes - 1; k >= 0; --k) u = u << 8 | b[k];
    if (t.is_signed && (u >> (8 * t.bytes - 1)) & 1)  // sign-extend
      return static_cast<double>(
          static_cast<std::int64_t>(u | (~std::uint64_t{0} << (8 * t.bytes - 1))));
    return static_cast<double>(u);
  }

  // Throws when anything but blanks follows the last element.
  void expect_end() {
    if (format_ == Format::Ascii) {
      while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) ++pos_;
      if (pos_ < bytes_.size())
        throw SceneError(name_ + ": line " + std::to_string(line_) +
                         ": text after the last element the header declares");
    } else if (pos_ < bytes_.size()) {
      throw SceneError(name_ + ": " + std::to_string(bytes_.size() - pos_) +
                       " bytes after the last element the header declares");
    }
  }

  std::uint64_t remaining() const { return bytes_.size() - pos_; }
  void set_line(int line) { line_ = line; }  // the ASCII body's first line

 private:
  double ascii(const Type& t, const std::string& what) {
    for (;;) {
      while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) {
        if (bytes_[pos_] == '\n') ++line_;
        ++pos_;
      }
      // A "comment" line in the body (not in the PLY grammar, but written by some tools, the
      // Stanford bunny's reconstructions among them) is read past.
      const bool line_start = pos_ == 0 || bytes_[pos_ - 1] == '\n';
      if (!line_start || bytes_.compare(pos_, 7, "comment") != 0) break;
      while (pos_ < bytes_.size() && bytes_[pos_] != '\n') ++pos_;
    }
    if (pos_ >= bytes_.size())
      throw SceneError(name_ + ": " + what + ": the file ends inside it (truncated)");
    size_t end = pos_;
    while (end < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[end]))) ++end;
    const std::string_view token(bytes_.data() + pos_, end - pos_);
    pos_ = end;
    double x = 0.0;
    if (t.is_float) {
      if (const std::string why = parse_finite(token, x); !why.empty())
        throw SceneError(name_ + ": line " + std::to_string(line_) + ": " + what + ": " + why);
      return x;
    }
    std::int64_t i = 0;
    if (const std::string why = parse_integer(token, i); !why.empty())
      throw SceneError(name_ + ": line " + std::to_string(line_) + ": " + what + ": " + why);
    return static_cast<double>(i);
  }

  const std::string& bytes_;
  size_t pos_;
  Format format_;
  std::string name_;
  int line_ = 0;
};

}  // namespace

bool looks_like_ply(const std::string& head) {
  return head.compare(0, 4, "ply\n") == 0 || head.compare(0, 5, "ply\r\n") == 0;
}

Scene load_ply_bytes(const std::string& bytes, const std::string& name, LoadReport* report_out,
                     const LoadOptions& options) {
  // ---- Header ----
  const size_t header_end = bytes.find("end_header");
  if (!looks_like_ply(bytes) || header_end == std::string::npos)
    throw SceneError(name + ": not a PLY file (no 'ply' ... 'end_header' header)");
  std::optional<Format> format;
  std::vector<Element> elements;
  size_t pos = 0;
  int line = 0;
  for (;;) {
    const size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos)
      throw SceneError(name + ": line " + std::to_string(line + 1) +
                       ": the header ends without 'end_header'");
    ++line;
    const std::vector<std::string_view> tok = split(std::string_view(bytes).substr(pos, eol - pos));
    pos = eol + 1;
    const auto where = [&] { return name + ": line " + std::to_string(line) + ": "; };
    if (tok.empty()) continue;
    if (line == 1) continue;  // "ply"
    if (tok[0] == "end_header") break;
    if (tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "format") {
      if (tok.size() != 3 || tok[2] != "1.0")
        throw SceneError(where() +
                         "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      if (tok[1] == "ascii")
        format = Format::Ascii;
      else if (tok[1] == "binary_little_endian")
        format = Format::Little;
      else if (tok[1] == "binary_big_endian")
        format = Format::Big;
      else
        throw SceneError(where() + "unknown format '" + std::string(tok[1]) + "'");
      continue;
    }
    if (tok[0] == "element") {
      std::int64_t n = -1;
      if (tok.size() != 3 || !parse_integer(tok[2], n).empty() || n < 0)
        throw SceneError(where() + "expected 'element NAME COUNT' with a count >= 0");
      elements.push_back({std::string(tok[1]), static_cast<std::uint64_t>(n), {}, line});
      continue;
    }
    if (tok[0] == "property") {
      if (elements.empty()) throw SceneError(where() + "a property before any element");
      Property p;
      if (tok.size() == 5 && tok[1] == "list") {
        const auto c = type_named(tok[2]), t = type_named(tok[3]);
        if (!c || !t || c->is_float)
          throw SceneError(where() +
                           "expected 'property list COUNT_TYPE ITEM_TYPE NAME' with an "
                           "integer count type");
        p = {std::string(tok[4]), *t, true, *c};
      } else if (tok.size() == 3) {
        const auto t = type_named(tok[1]);
        if (!t) throw SceneError(where() + "unknown property type '" + std::string(tok[1]) + "'");
        p = {std::string(tok[2]), *t, false, {}};
      } else {
        throw SceneError(where() + "expected 'property TYPE NAME' or 'property list ...'");
      }
      elements.back().properties.push_back(p);
      continue;
    }
    throw SceneError(where() + "unknown header keyword '" + std::string(tok[0]) + "'");
  }
  if (!format) throw SceneError(name + ": the header has no 'format' line");

  // ---- Body ----
  Body body(bytes, pos, *format, name);
  body.set_line(line + 1);
  LoadReport report;
  SceneBuilder out(name, report);
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3d> colours;  // with --vertex-colors-as-reflectance
  std::vector<char> coloured;
  std::uint64_t faces = 0;
  for (const Element& e : elements) {
    // Every instance takes at least one byte (or an ASCII token and a blank): a count above
    // what is left is refused before anything is allocated for it.
    if (e.count > body.remaining())
      throw SceneError(name + ": line " + std::to_string(e.line) + ": " + std::to_string(e.count) +
                       " " + e.name + " elements cannot fit in the " +
                       std::to_string(body.remaining()) + " bytes after the header");
    const bool is_vertex = e.name == "vertex", is_face = e.name == "face";
    int ix = -1, iy = -1, iz = -1, ir = -1, ig = -1, ib = -1, iface = -1;
    for (size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      const int i = static_cast<int>(k);
      if (is_vertex && !p.list) {
        if (p.name == "x") ix = i;
        if (p.name == "y") iy = i;
        if (p.name == "z") iz = i;
        if (p.name == "red" || p.name == "r") ir = i;
        if (p.name == "green" || p.name == "g") ig = i;
        if (p.name == "blue" || p.name == "b") ib = i;
      }
      if (is_face && p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) iface = i;
    }
    if (is_vertex && (ix < 0 || iy < 0 || iz < 0))
      throw SceneError(name + ": line " + std::to_string(e.line) +
                       ": the vertex element has no x, y and z properties");
    if (is_face && iface < 0)
      throw SceneError(name + ": line " + std::to_string(e.line) +
                       ": the face element has no list property vertex_indices");
    const bool colour =
        is_vertex && options.vertex_colors_as_reflectance && ir >= 0 && ig >= 0 && ib >= 0;
    if (is_vertex) {
      vertices.reserve(e.count);
      if (colour) colours.reserve(e.count);
    }
    std::vector<std::int64_t> indices;
    for (std::uint64_t n = 0; n < e.count; ++n) {
      const std::string what = e.name + " " + std::to_string(n + 1);  // 1-based, as STL facets
      double xyz[3] = {0, 0, 0}, rgb[3] = {0, 0, 0};
      indices.clear();
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const Property& p = e.properties[k];
        const int i = static_cast<int>(k);
        if (p.list) {
          const double c = body.value(p.count, what);
          if (c < 0 || c > static_cast<double>(body.remaining()))
            throw SceneError(name + ": " + what + ": a list of " + std::to_string(c) +
                             " items cannot fit in the file");
          for (std::int64_t m = 0; m < static_cast<std::int64_t>(c); ++m) {
            const double v = body.value(p.type, what);
            if (i == iface) indices.push_back(static_cast<std::int64_t>(v));
          }
          continue;
        }
        const double v = body.value(p.type, what);
        if (i == ix) xyz[0] = v;
        if (i == iy) xyz[1] = v;
        if (i == iz) xyz[2] = v;
        if (i == ir) rgb[0] = p.type.is_float ? v : v / 255.0;
        if (i == ig) rgb[1] = p.type.is_float ? v : v / 255.0;
        if (i == ib) rgb[2] = p.type.is_float ? v : v / 255.0;
      }
      if (is_vertex) {
        const Eigen::Vector3d x(xyz[0], xyz[1], xyz[2]);
        if (!x.allFinite()) throw SceneError(name + ": " + what + ": a coordinate is not finite");
        if (x.cwiseAbs().maxCoeff() > 1e50)
          throw SceneError(name + ": " + what + ": a coordinate beyond 1e50 (rescale the scene)");
        vertices.push_back(x);
        if (colour) {
          const Eigen::Vector3d c(rgb[0], rgb[1], rgb[2]);
          if (!(c.minCoeff() >= 0.0 && c.maxCoeff() <= 1.0))
            throw SceneError(name + ": " + what +
                             ": a colour outside [0, 1] cannot be a reflectance");
          colours.push_back(c);
        }
      }
      if (is_face) {
        ++faces;
        std::vector<Eigen::Vector3d> poly;
        std::int64_t previous = -1;
        Eigen::Vector3d rho = Eigen::Vector3d::Zero();
        int summed = 0;
        for (const std::int64_t v : indices) {
          if (v < 0 || v >= static_cast<std::int64_t>(vertices.size()))
            throw SceneError(name + ": " + what + ": vertex index " + std::to_string(v) +
                             " out of range (" + std::to_string(vertices.size()) +
                             " vertices before it)");
          if (v == previous) continue;  // a repeated corner collapses
          previous = v;
          poly.push_back(vertices[v]);
          if (!colours.empty()) rho += colours[v], ++summed;
        }
        if (poly.size() > 1 && poly.front() == poly.back()) poly.pop_back();
        if (indices.size() < 3)
          throw SceneError(name + ": " + what + ": a face needs 3 corners, it has " +
                           std::to_string(indices.size()));
        const size_t before = out.scene().faces.size();
        out.add_polygon(poly, -1, what);
        if (!colours.empty())
          for (size_t f = before; f < out.scene().faces.size(); ++f)
            out.scene().faces[f].rho = rho / static_cast<double>(summed);
      }
    }
  }
  body.expect_end();
  if (faces == 0)
    throw SceneError(name + ": no faces: a point cloud cannot be meshed into patches");
  if (!out.scene().faces.empty()) out.assign_components("ply");
  Scene scene = out.finish(options, 1);  // scanned and modelled meshes: y up
  if (report_out) *report_out = std::move(report);
  return scene;
}

Scene load_ply(const std::string& path, LoadReport* report, const LoadOptions& options) {
  Scene scene = load_ply_bytes(read_file_bytes(path), path, report, options);
  add_camera_sidecar(scene, path);
  return scene;
}

}  // namespace lambert
