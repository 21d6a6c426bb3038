#include "io/ply.hpp"

#include <cmath>
#include <cstdio>
#include <ostream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "io/tonemap.hpp"

namespace lambert {

void write_ply_values(const std::string& path, const PatchMesh& mesh, const VertexField& field,
                      const PlyValues& values) {
  LAMBERT_CHECK(field.patch_corners.size() == mesh.patches.size() &&
                    field.values.rows() == field.size() &&
                    values.colours.size() == static_cast<size_t>(field.size()),
                "ply: vertex field does not match the mesh");
  write_stream_atomically(path, [&](std::ostream& out) {
    out << "ply\nformat ascii 1.0\n";
    out << "comment written by lambert " << LAMBERT_VERSION << "\n";
    for (const auto& c : values.comments) out << "comment " << c << "\n";
    out << "element vertex " << field.size() << "\n";
    for (const char* p : {"x", "y", "z", "nx", "ny", "nz"}) out << "property float " << p << "\n";
    for (const char* p : {"red", "green", "blue"}) out << "property uchar " << p << "\n";
    for (const auto& p : values.names) out << "property float " << p << "\n";
    out << "element face " << mesh.size() << "\n";
    out << "property list uchar int vertex_indices\nend_header\n";
    char buf[256];
    for (std::int32_t k = 0; k < field.size(); ++k) {
      const Eigen::Vector3d v = field.values.row(k).transpose();
      const auto& rgb = values.colours[k];
      const auto& p = field.positions[k];
      const auto& n = field.normals[k];
      std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g %.6g %.6g %.6g %d %d %d %.9g %.9g %.9g\n",
                    p.x(), p.y(), p.z(), n.x(), n.y(), n.z(), rgb[0], rgb[1], rgb[2], v[0], v[1],
                    v[2]);
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

void write_ply(const std::string& path, const PatchMesh& mesh, const VertexField& field, double ev,
               const std::string& comment) {
  PlyValues values;
  values.names = {"radiosity_r", "radiosity_g", "radiosity_b"};
  char buf[256];
  std::snprintf(buf, sizeof buf, "colours: sRGB OETF of clip(2^EV * B/pi), EV = %.6f (scale %.9g)",
                ev, std::exp2(ev));
  values.comments = {buf, "radiosity_r/g/b: linear radiosity B, units of the scene's emission E"};
  if (!comment.empty()) values.comments.push_back(comment);
  values.colours.reserve(field.size());
  for (std::int32_t k = 0; k < field.size(); ++k)
    values.colours.push_back(to_srgb8(field.values.row(k).transpose() / M_PI, ev));
  write_ply_values(path, mesh, field, values);
}

}  // namespace lambert
