#include "io/obj_parser.hpp"

#include <cmath>
#include <limits>
#include <set>
#include <string_view>
#include <unordered_map>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/strict_number.hpp"

namespace lambert {
namespace {

// Statements OBJ can hold that radiosity does not use: skipped with a count.
const std::set<std::string, std::less<>> kSkipped = {
    "vt",      "vn",     "vp",    "p",          "l",          "curv",  "curv2", "surf",
    "cstype",  "deg",    "bmat",  "step",       "parm",       "trim",  "hole",  "scrv",
    "sp",      "end",    "con",   "s",          "mg",         "lod",   "bevel", "c_interp",
    "d_interp", "shadow_obj", "trace_obj", "ctech", "stech", "maplib", "usemap", "call",
    "csh",     "res"};

// The colour of a vertex that has none (ObjColors::of_vertex).
const Eigen::Vector3d kNoColor = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

class ObjParser {
 public:
  ObjParser(std::istream& in, const std::string& name) : lines_(in, name) {}

  ObjData run() {
    std::string_view line;
    while (lines_.next(line)) {
      split_tokens(line, tok_);
      if (tok_.empty()) continue;
      statement();
    }
    if (!out_.colors.of_vertex.empty())  // vertices after the last coloured one have none
      out_.colors.of_vertex.resize(out_.vertices.size(), kNoColor);
    return std::move(out_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError(lines_.where() + ": " + what);
  }

  void statement() {
    const std::string_view key = tok_[0];
    if (key == "v") vertex();
    else if (key == "f" || key == "fo") face();
    else if (key == "g" || key == "o") group_ = group_id(tok_.size() > 1 ? join_tokens(tok_, 1) : "default");
    else if (key == "usemtl") material_ = material_id(join_tokens(tok_, 1));
    else if (key == "mtllib") mtllib();
    else if (kSkipped.count(key)) skip(std::string(key));
    else fail("malformed OBJ: unknown statement " + quoted(key));
  }

  void skip(const std::string& what) {
    ObjSkipped& s = out_.skipped[what];
    if (s.count++ == 0) s.first_line = lines_.line_number();
    if (what == "vt") ++texcoords_;
    if (what == "vn") ++normals_;
  }

  void vertex() {
    // v x y z, v x y z w (a rational-curve weight, unused) or v x y z r g b (a colour).
    const size_t n = tok_.size() - 1;
    if (n != 3 && n != 4 && n != 6)
      fail("malformed vertex: expected 3 coordinates (then a weight or r g b), got " +
           std::to_string(n) + " numbers");
    double x[6];
    for (size_t k = 0; k < n; ++k) {
      const std::string why = parse_finite(tok_[k + 1], x[k]);
      if (!why.empty()) {
        if (why == "not finite") fail("vertex coordinate " + quoted(tok_[k + 1]) + " is not finite");
        fail("malformed vertex: " + quoted(tok_[k + 1]) + " is " + why);
      }
      if (k < 3 && std::abs(x[k]) > kMaxObjCoordinate)
        fail("vertex coordinate " + quoted(tok_[k + 1]) +
             " is beyond +-1e50, where areas and form factors overflow: rescale the scene");
    }
    if (out_.vertices.size() >= static_cast<size_t>(std::numeric_limits<std::int32_t>::max()))
      fail("more than 2^31 - 1 vertices");
    if (n == 6) color(Eigen::Vector3d(x[3], x[4], x[5]));
    if (n == 4) skip("vertex weights");
    out_.vertices.emplace_back(x[0], x[1], x[2]);
  }

  // The colour of the vertex being added (counted as skipped: the loader uses it only
  // with --vertex-colors-as-reflectance).
  void color(const Eigen::Vector3d& c) {
    skip("vertex colours");
    ObjColors& cs = out_.colors;
    const int line = lines_.line_number();
    if (cs.of_vertex.empty()) {
      cs.first_line = line;
      cs.max = c.maxCoeff();
      cs.min = c.minCoeff();
      cs.max_line = cs.min_line = line;
    }
    if (c.maxCoeff() > cs.max) {
      cs.max = c.maxCoeff();
      cs.max_line = line;
    }
    if (c.minCoeff() < cs.min) {
      cs.min = c.minCoeff();
      cs.min_line = line;
    }
    cs.all_integers = cs.all_integers && (c.array() == c.array().round()).all();
    cs.of_vertex.resize(out_.vertices.size(), kNoColor);
    cs.of_vertex.push_back(c);
  }

  // Resolves one index (1-based, or negative counting back) against `count` defined so far.
  std::int32_t index(std::string_view tok, std::string_view part, std::int64_t count,
                     const char* what) const {
    std::int64_t v = 0;
    const std::string why = parse_integer(part, v);
    if (!why.empty()) fail("malformed face index " + quoted(tok) + ": " + quoted(part) + " is " + why);
    const std::int64_t resolved = v > 0 ? v : count + v + 1;  // v < 0 may underflow only to < 1
    if (v == 0 || resolved < 1 || resolved > count)
      fail(std::string("face ") + what + "index " + std::to_string(v) + " out of range (" +
           std::to_string(count) + " " + (what[0] ? "defined" : "vertices defined") + " so far)");
    return static_cast<std::int32_t>(resolved - 1);
  }

  void face() {
    ObjFace f;
    f.group = group_ < 0 ? group_id("default") : group_;
    f.material = material_;
    f.line = lines_.line_number();
    f.vertices.reserve(tok_.size() - 1);
    const auto nv = static_cast<std::int64_t>(out_.vertices.size());
    for (size_t k = 1; k < tok_.size(); ++k) {
      const std::string_view t = tok_[k];
      const size_t s1 = t.find('/');
      f.vertices.push_back(index(t, t.substr(0, s1), nv, ""));
      if (s1 == std::string_view::npos) continue;
      const size_t s2 = t.find('/', s1 + 1);
      const std::string_view vt = t.substr(s1 + 1, s2 == std::string_view::npos ? s2 : s2 - s1 - 1);
      if (!vt.empty()) index(t, vt, texcoords_, "texture-coordinate ");
      if (s2 == std::string_view::npos) continue;
      const std::string_view vn = t.substr(s2 + 1);
      if (vn.find('/') != std::string_view::npos) fail("malformed face index " + quoted(t));
      if (!vn.empty()) index(t, vn, normals_, "normal ");
    }
    if (f.vertices.size() < 3)
      fail("face has " + std::to_string(f.vertices.size()) + " vertices, needs at least 3");
    out_.faces.push_back(std::move(f));
  }

  void mtllib() {
    if (tok_.size() < 2) fail("mtllib without a file name");
    ObjMtllib lib;
    lib.line = lines_.line_number();
    lib.rest = join_tokens(tok_, 1);
    for (size_t k = 1; k < tok_.size(); ++k) lib.tokens.emplace_back(tok_[k]);
    out_.mtllibs.push_back(std::move(lib));
  }

  std::int32_t group_id(const std::string& name) {
    auto [it, added] = group_ids_.emplace(name, static_cast<std::int32_t>(out_.groups.size()));
    if (added) out_.groups.push_back(name);
    return it->second;
  }

  std::int32_t material_id(const std::string& name) {
    auto [it, added] =
        material_ids_.emplace(name, static_cast<std::int32_t>(out_.materials.size()));
    if (added) out_.materials.push_back({name, lines_.line_number()});
    return it->second;
  }

  LineReader lines_;
  std::vector<std::string_view> tok_;
  ObjData out_;
  std::unordered_map<std::string, std::int32_t> group_ids_, material_ids_;
  std::int32_t group_ = -1, material_ = -1;
  std::int64_t texcoords_ = 0, normals_ = 0;
};

}  // namespace

ObjData parse_obj(std::istream& in, const std::string& name) { return ObjParser(in, name).run(); }

}  // namespace lambert
