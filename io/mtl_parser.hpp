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
  Eigen::Vector3d ks = Eigen::Vector3d::Zero();  ///< specular reflectance (no Ks: 0)
  Eigen::Vector3d tf = Eigen::Vector3d::Ones();  ///< transmission filter (no Tf: 1)
  double ns = 0.0;         ///< specular exponent
  double ni = 1.0;         ///< index of refraction (MTL's default 1)
  double dissolve = 1.0;   ///< d (Tr = 1 - d): 1 is opaque
  int illum = -1;          ///< illumination model 0..10, -1 when absent
  std::string file;
  int line = 0, kd_line = 0, ke_line = 0, ks_line = 0, tf_line = 0, ns_line = 0, ni_line = 0,
      dissolve_line = 0, illum_line = 0;
};

/// Parses MTL text: `newmtl NAME`; `Kd`, `Ke`, `Ks`, `Tf` as `r g b` or one grey value;
/// `Ns`, `Ni`, `d`, `Tr` (= 1 - d) one number; `illum` an integer 0..10. Every other
/// statement is ignored (the spectral `spectral` and `xyz` forms of the colours are
/// refused). Numbers are read by parse_finite and must be finite; Ns >= 0, d and Tr in
/// [0, 1] (Ni > 0 is required of dielectrics by the loader: exporters write `Ni 0` on
/// diffuse materials). Statements other than Kd and Ke before any newmtl are ignored.
/// Throws SceneError "name:line: what is wrong" (IoError on a read error).
std::vector<MtlMaterial> parse_mtl(std::istream& in, const std::string& name);

}  // namespace lambert
