#include "bench/obj_writer.hpp"

#include <cstdio>
#include <filesystem>
#include <ostream>
#include <vector>

#include "core/atomic_file.hpp"

namespace lambert::bench {
namespace {

void put(std::ostream& out, const char* key, const Eigen::Vector3d& v) {
  char line[128];
  std::snprintf(line, sizeof line, "%s %.17g %.17g %.17g\n", key, v.x(), v.y(), v.z());
  out << line;
}

}  // namespace

void write_obj(const Scene& scene, const std::string& obj_path) {
  const std::filesystem::path obj(obj_path);
  const std::filesystem::path mtl = std::filesystem::path(obj).replace_extension(".mtl");
  const std::filesystem::path camera = std::filesystem::path(obj).replace_extension(".camera");
  write_stream_atomically(mtl.string(), [&](std::ostream& out) {
    out << "# " << scene.source << ": Kd = reflectance, Ke = emitted radiosity\n";
    for (const Material& m : scene.materials) {
      out << "\nnewmtl " << m.name << "\n";
      put(out, "Kd", m.rho);
      put(out, "Ke", m.emission);
    }
  });
  std::vector<std::vector<std::size_t>> faces_of(scene.surfaces.size());
  for (std::size_t f = 0; f < scene.faces.size(); ++f)
    faces_of[scene.faces[f].surface].push_back(f);
  write_stream_atomically(obj.string(), [&](std::ostream& out) {
    out << "# " << scene.source << "; fronts counter-clockwise\n";
    out << "mtllib " << mtl.filename().string() << "\n";
    for (const Eigen::Vector3d& v : scene.vertices) put(out, "v", v);
    for (std::size_t s = 0; s < scene.surfaces.size(); ++s) {
      if (faces_of[s].empty()) continue;
      out << "\ng " << scene.surfaces[s].name << "\nusemtl "
          << scene.materials[scene.surfaces[s].material].name << "\n";
      for (const std::size_t f : faces_of[s]) {
        out << 'f';
        for (const auto v : scene.faces[f].vertices) out << ' ' << v + 1;
        out << '\n';
      }
    }
  });
  if (!scene.camera.defined) return;
  write_stream_atomically(camera.string(), [&](std::ostream& out) {
    const Camera& c = scene.camera;
    put(out, "eye", c.eye);
    put(out, "look_at", c.look_at);
    put(out, "up", c.up);
    char line[64];
    std::snprintf(line, sizeof line, "vfov %.17g\n", c.vfov_degrees);
    out << line;
  });
}

}  // namespace lambert::bench
