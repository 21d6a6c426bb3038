#include "io/ply.hpp"

#include <cmath>
#include <cstdio>
#include <ostream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/tonemap.hpp"

namespace lambert {

void write_ply(const std::string& path, const PatchMesh& mesh, const VertexField& field, double ev,
               const std::string& comment) {
  LAMBERT_CHECK(
      field.patch_corners.size() == mesh.patches.size() && field.values.rows() == field.size(),
      "ply: vertex field does not match the mesh");
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "ply\nformat ascii 1.0\n";
    out << "comment written by lambert " << LAMBERT_VERSION << "\n";
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "comment colours: sRGB OETF of clip(2^EV * B/pi), EV = %.6f (scale %.9g)", ev,
                  std::exp2(ev));
    out << buf << "\n";
    out << "comment radiosity_r/g/b: linear radiosity B, units of the scene's emission E\n";
    if (!comment.empty()) out << "comment " << comment << "\n";
    out << "element vertex " << field.size() << "\n";
    for (const char* p : {"x", "y", "z", "nx", "ny", "nz"}) out << "property float " << p << "\n";
    for (const char* p : {"red", "green", "blue"}) out << "property uchar " << p << "\n";
    for (const char* p : {"radiosity_r", "radiosity_g", "radiosity_b"})
      out << "property float " << p << "\n";
    out << "element face " << mesh.size() << "\n";
    out << "property list uchar int vertex_indices\nend_header\n";
    for (std::int32_t k = 0; k < field.size(); ++k) {
      const Eigen::Vector3d B = field.values.row(k).transpose();
      const auto rgb = to_srgb8(B / M_PI, ev);
      const auto& p = field.positions[k];
      const auto& n = field.normals[k];
      std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g %.6g %.6g %.6g %d %d %d %.9g %.9g %.9g\n",
                    p.x(), p.y(), p.z(), n.x(), n.y(), n.z(), rgb[0], rgb[1], rgb[2], B[0], B[1],
                    B[2]);
      out << buf;
    }
    for (std::int32_t i = 0; i < mesh.size(); ++i) {
      const Patch& patch = mesh.patches[i];
      out << patch.vertex_count;
      for (int k = 0; k < patch.vertex_count; ++k) out << ' ' << field.patch_corners[i][k];
      out << '\n';
    }
  });
}

}  // namespace lambert
