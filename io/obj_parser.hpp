#pragma once
// Wavefront OBJ text -> the statements radiosity uses, every index checked. Private to io/
// (the loader, io/obj_loader.hpp, turns it into a Scene).

#include <Eigen/Core>
#include <cstdint>
#include <istream>
#include <map>
#include <string>
#include <vector>

namespace lambert {

/// One `f` statement: corners resolved to 0-based vertex indices, all in range.
struct ObjFace {
  std::vector<std::int32_t> vertices;
  std::int32_t group = 0;      ///< index into ObjData::groups
  std::int32_t material = -1;  ///< index into ObjData::materials; -1 = no usemtl before it
  int line = 0;
};

/// A distinct `usemtl` name (trimmed, inner blanks as single spaces; "" = usemtl without
/// a name) and the line of its first use.
struct ObjMaterialUse {
  std::string name;
  int line = 0;
};

/// An `mtllib` statement: its line, the whole (normalized) rest and its tokens.
struct ObjMtllib {
  int line = 0;
  std::string rest;
  std::vector<std::string> tokens;
};

/// A statement kind that was skipped: how often, and its first line.
struct ObjSkipped {
  int count = 0;
  int first_line = 0;
};

/// Vertex colours (`v x y z r g b`), kept for --vertex-colors-as-reflectance.
struct ObjColors {
  /// Per vertex once any vertex has a colour (else empty); NaN for a vertex without one.
  std::vector<Eigen::Vector3d> of_vertex;
  int first_line = 0;       ///< line of the first colour (0 = none)
  double max = 0.0;         ///< largest component of any colour
  int max_line = 0;         ///< its line
  double min = 0.0;         ///< smallest component of any colour
  int min_line = 0;         ///< its line
  bool all_integers = true; ///< every component is a whole number (a 0..255 file)
};

/// What the parser kept of an OBJ file.
struct ObjData {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::string> groups;  ///< distinct group names (`o`/`g`), first use first
  std::vector<ObjMaterialUse> materials;
  std::vector<ObjFace> faces;
  std::vector<ObjMtllib> mtllibs;
  ObjColors colors;
  std::map<std::string, ObjSkipped> skipped;  ///< statement (or "vertex colours") -> count
};

/// Parses OBJ text. Lines end at LF, CRLF or CR (io/line_reader.hpp); numbers are read by
/// parse_finite (io/strict_number.hpp); coordinates beyond +-kMaxObjCoordinate are refused.
/// Faces take any number (>= 3) of `v`, `v/vt`, `v//vn` or `v/vt/vn` corners, negative
/// indices counting back from the last vertex; every index must name an element defined
/// before it. Throws SceneError "name:line: what is wrong" (IoError on a read error).
ObjData parse_obj(std::istream& in, const std::string& name);

/// Largest accepted coordinate magnitude. Form-factor kernels and patch areas take fourth
/// powers of distances (|d|^4 of the point-to-point kernel, products of two areas): with
/// coordinates up to 1e50 these stay below (2 sqrt(3) 1e50)^4 ~ 1e202, far from double's
/// 1.8e308, while any physical scene in any unit is many orders of magnitude smaller.
constexpr double kMaxObjCoordinate = 1e50;

}  // namespace lambert
