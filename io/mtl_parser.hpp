#pragma once
// Wavefront MTL text -> the materials' Kd and Ke. Private to io/ (see io/obj_loader.hpp).

#include <Eigen/Core>
#include <istream>
#include <string>
#include <vector>

namespace lambert {

/// One `newmtl` with where its statements are (lines 0 when absent).
struct MtlMaterial {
  std::string name;  ///< trimmed, inner blanks as single spaces
  Eigen::Vector3d kd = Eigen::Vector3d::Zero();  ///< no Kd: black
  Eigen::Vector3d ke = Eigen::Vector3d::Zero();
  std::string file;
  int line = 0, kd_line = 0, ke_line = 0;
};

/// Parses MTL text: `newmtl NAME`, `Kd r g b` or `Kd r` (grey), `Ke` likewise; every other
/// statement is ignored. Numbers are read by parse_finite and must be finite. Throws
/// SceneError "name:line: what is wrong" (IoError on a read error).
std::vector<MtlMaterial> parse_mtl(std::istream& in, const std::string& name);

}  // namespace lambert
