// Writes a scene of the generated family (bench/scene_generator.hpp: the Cornell box with
// many tessellated ellipsoids) as OBJ + MTL + camera sidecar, for `lambert run`.
// Usage: make_scene [--triangles N] [--seed S] -o scene.obj

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "bench/obj_writer.hpp"
#include "bench/scene_generator.hpp"
#include "core/error.hpp"
#include "core/log.hpp"

using namespace lambert;

int main(int argc, char** argv) {
  set_log_level(LogLevel::Quiet);
  long long triangles = 1000;
  unsigned long long seed = 1;
  std::string out;
  bool usage = false;
  for (int a = 1; a < argc; ++a) {
    if (!std::strcmp(argv[a], "--triangles") && a + 1 < argc)
      triangles = std::atoll(argv[++a]);
    else if (!std::strcmp(argv[a], "--seed") && a + 1 < argc)
      seed = std::strtoull(argv[++a], nullptr, 10);
    else if (!std::strcmp(argv[a], "-o") && a + 1 < argc)
      out = argv[++a];
    else
      usage = true;
  }
  if (usage || out.empty()) {
    std::fprintf(stderr, "usage: make_scene [--triangles N] [--seed S] -o scene.obj\n");
    return 2;
  }
  try {
    const Scene scene = bench::cornell_with_objects(triangles, seed);
    bench::write_obj(scene, out);
    std::printf("%s: %lld triangles in %zu faces, %zu surfaces, %zu vertices\n", out.c_str(),
                static_cast<long long>(bench::triangle_count(scene)), scene.faces.size(),
                scene.surfaces.size(), scene.vertices.size());
  } catch (const UsageError& e) {
    std::fprintf(stderr, "make_scene: %s\n", e.what());
    return 2;
  } catch (const Error& e) {
    std::fprintf(stderr, "make_scene: %s\n", e.what());
    return 1;
  }
  return 0;
}
