#include "io/mtl_parser.hpp"

#include <string_view>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/strict_number.hpp"

namespace lambert {

std::vector<MtlMaterial> parse_mtl(std::istream& in, const std::string& name) {
  std::vector<MtlMaterial> out;
  LineReader lines(in, name);
  std::vector<std::string_view> tok;
  std::string_view line;
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
    } else if (tok[0] == "Kd" || tok[0] == "Ke") {
      const std::string key(tok[0]);
      if (out.empty()) throw SceneError(lines.where() + ": " + key + " before any newmtl");
      MtlMaterial& m = out.back();
      if (tok.size() != 2 && tok.size() != 4)
        throw SceneError(lines.where() + ": malformed " + key +
                         ": expected 3 numbers (r g b) or 1 (grey)");
      Eigen::Vector3d c;
      for (size_t k = 1; k < tok.size(); ++k) {
        const std::string why = parse_finite(tok[k], c[static_cast<int>(k) - 1]);
        if (why == "not finite")
          throw SceneError(lines.where() + ": material '" + m.name + "': " + key + " value '" +
                           std::string(tok[k]) + "' must be finite");
        if (!why.empty())
          throw SceneError(lines.where() + ": malformed " + key + ": '" + std::string(tok[k]) +
                           "' is " + why);
      }
      if (tok.size() == 2) c.setConstant(c[0]);
      (key == "Kd" ? m.kd : m.ke) = c;
      (key == "Kd" ? m.kd_line : m.ke_line) = lines.line_number();
    }
  }
  return out;
}

}  // namespace lambert
