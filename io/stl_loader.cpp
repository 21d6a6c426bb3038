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
#include "io/model_loader.hpp"
#include "io/obj_loader.hpp"
#include "io/obj_parser.hpp"
#include "io/ply_loader.hpp"
#include "io/soup_builder.hpp"
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
    return stem_of(name_, "stl") + (block > 1 ? "_" + std::to_string(block) : "");
  }

  LineReader lines_;
  std::string name_;
  SceneBuilder& out_;
  std::vector<std::string_view> tok_;
};

// Union-find root with path halving.

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
  out.assign_components("stl");
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
  Scene scene = out.finish(options, 2);  // CAD: z up
  if (report_out) *report_out = std::move(report);
  return scene;
}

Scene load_stl(const std::string& path, LoadReport* report, const LoadOptions& options) {
  Scene scene = load_stl_bytes(read_file_bytes(path), path, report, options);
  add_camera_sidecar(scene, path);
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
    if (looks_like_ply(head)) return load_ply(path, report, options);
    if (looks_like_model(path, head)) return load_model(path, report, options);
    if (!ec && looks_like_stl(head, size)) return load_stl(path, report, options);
  }
  return load_obj(path, report, options);  // also reports a missing or unreadable file
}

}  // namespace lambert
