#include "io/mtl_parser.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string_view>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/strict_number.hpp"

namespace lambert {

namespace {

// "name:line: ..." helpers for one statement's numbers.
struct Statement {
  const LineReader& lines;
  const std::vector<std::string_view>& tok;
  const MtlMaterial& m;

  std::string key() const { return std::string(tok[0]); }
  [[noreturn]] void fail(const std::string& what) const {
    throw SceneError(lines.where() + ": material '" + m.name + "': " + what);
  }
  double number(size_t k) const {
    double x = 0.0;
    const std::string why = parse_finite(tok[k], x);
    if (why == "not finite")
      fail(key() + " value '" + std::string(tok[k]) + "' must be finite");
    if (!why.empty())
      throw SceneError(lines.where() + ": malformed " + key() + ": '" + std::string(tok[k]) +
                       "' is " + why);
    return x;
  }
  Eigen::Vector3d color() const {
    if (tok.size() >= 2 && (tok[1] == "spectral" || tok[1] == "xyz"))
      fail(key() + " " + std::string(tok[1]) + " is not supported: give r g b");
    if (tok.size() != 2 && tok.size() != 4)
      throw SceneError(lines.where() + ": malformed " + key() +
                       ": expected 3 numbers (r g b) or 1 (grey)");
    Eigen::Vector3d c;
    for (size_t k = 1; k < tok.size(); ++k) c[static_cast<int>(k) - 1] = number(k);
    if (tok.size() == 2) c.setConstant(c[0]);
    return c;
  }
  double scalar() const {
    if (tok.size() != 2)
      throw SceneError(lines.where() + ": malformed " + key() + ": expected 1 number");
    return number(1);
  }
};

}  // namespace

std::vector<MtlMaterial> parse_mtl(std::istream& in, const std::string& name) {
  std::vector<MtlMaterial> out;
  LineReader lines(in, name);
  std::vector<std::string_view> tok;
  std::string_view line;
  static const char* const kKeys[] = {"Kd", "Ke", "Ks", "Tf", "Ns", "Ni", "d", "Tr", "illum"};
  while (lines.next(line)) {
    split_tokens(line, tok);
    if (tok.empty()) continue;
    if (tok[0] == "newmtl") {
      MtlMaterial m;
      m.name = join_tokens(tok, 1);
      if (m.name.empty()) throw SceneError(lines.where() + ": newmtl without a material name");
      m.file = name;
      m.line = lines.line_number();
      out.push_back(std::move(m));
      continue;
    }
    if (std::find(std::begin(kKeys), std::end(kKeys), tok[0]) == std::end(kKeys)) continue;
    const std::string key(tok[0]);
    // Kd and Ke before a newmtl have always been refused; the statements read since
    // specular materials stay ignored there, as they were before.
    if (out.empty() && key != "Kd" && key != "Ke") continue;
    if (out.empty()) throw SceneError(lines.where() + ": " + key + " before any newmtl");
    MtlMaterial& m = out.back();
    const Statement st{lines, tok, m};
    const int at = lines.line_number();
    if (key == "Kd") {
      m.kd = st.color(), m.kd_line = at;
    } else if (key == "Ke") {
      m.ke = st.color(), m.ke_line = at;
    } else if (key == "Ks") {
      m.ks = st.color(), m.ks_line = at;
    } else if (key == "Tf") {
      m.tf = st.color(), m.tf_line = at;
      if (m.tf.minCoeff() < 0.0 || m.tf.maxCoeff() > 1.0)
        st.fail("transmission filter Tf must lie in [0, 1] in every channel");
    } else if (key == "Ns") {
      m.ns = st.scalar(), m.ns_line = at;
      if (m.ns < 0.0) st.fail("specular exponent Ns must be >= 0");
    } else if (key == "Ni") {
      m.ni = st.scalar(), m.ni_line = at;  // > 0 is checked for dielectrics (obj_loader)
    } else if (key == "d" || key == "Tr") {
      // `d -halo f` is the one option form of d; its halo is not modelled.
      const double v = tok.size() == 3 && tok[1] == "-halo" ? st.number(2) : st.scalar();
      if (v < 0.0 || v > 1.0) st.fail(key + " must lie in [0, 1]");
      m.dissolve = key == "d" ? v : 1.0 - v, m.dissolve_line = at;
    } else {  // illum
      const double v = st.scalar();
      if (v != std::floor(v) || v < 0.0 || v > 10.0)
        st.fail("illum must be an integer from 0 to 10");
      m.illum = static_cast<int>(v), m.illum_line = at;
    }
  }
  return out;
}

}  // namespace lambert
