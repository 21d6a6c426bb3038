#include <algorithm>
#include <cstdio>
#include <iostream>

#include "apps/commands.hpp"

namespace lambert {

CLI::App* add_info_command(CLI::App& app, InfoOptions& opts) {
  auto* cmd = app.add_subcommand("info", "Describe a scene: surfaces, materials, emitters, meshing");
  opts.scene.default_patches = 2000;
  add_scene_options(cmd, opts.scene);
  add_run_options(cmd, opts.run);
  add_declared(cmd, "--list-surfaces", opts.list_surfaces);
  return cmd;
}

int run_info(const InfoOptions& opts) {
  apply_run_options(opts.run);
  if (opts.list_surfaces) {
    const Scene scene = load_scene_file(opts.scene);
    for (size_t s = 0; s < scene.surfaces.size(); ++s) {
      const Material& m = scene.material_of(static_cast<std::int32_t>(s));
      std::printf("%s\t%s\t%s\n", scene.surfaces[s].name.c_str(), m.name.c_str(),
                  m.emits() ? "yes" : "no");
    }
    return 0;
  }
  const LoadedScene loaded = load_scene(opts.scene, job_plan(opts.run));
  const Scene& scene = loaded.scene;
  const PatchMesh& mesh = loaded.mesh;

  std::printf("scene: %s\n", scene.source.c_str());
  std::printf("\nmaterials (%zu):\n", scene.materials.size());
  std::printf("  %-16s %-26s %-26s\n", "name", "rho (R G B)", "E (R G B, W/m^2)");
  for (const auto& m : scene.materials) {
    std::printf("  %-16s %8.4f %8.4f %8.4f  %8.4g %8.4g %8.4g", m.name.c_str(), m.rho[0],
                m.rho[1], m.rho[2], m.emission[0], m.emission[1], m.emission[2]);
    const Specular& sp = m.specular;
    if (sp.dielectric)
      std::printf("  dielectric Ni %.4g Tf %.4g %.4g %.4g", sp.ior, sp.transmission[0],
                  sp.transmission[1], sp.transmission[2]);
    else if (sp.any())
      std::printf("  mirror Ks %.4g %.4g %.4g", sp.reflectance[0], sp.reflectance[1],
                  sp.reflectance[2]);
    std::printf("\n");
  }

  std::vector<double> surface_area(scene.surfaces.size(), 0.0);
  std::vector<int> surface_patches(scene.surfaces.size(), 0);
  for (const auto& p : mesh.patches) {
    surface_area[p.surface] += p.area;
    ++surface_patches[p.surface];
  }
  std::printf("\nsurfaces (%zu):\n", scene.surfaces.size());
  std::printf("  %-16s %-10s %14s %8s\n", "name", "material", "area", "patches");
  double total = 0.0;
  for (size_t s = 0; s < scene.surfaces.size(); ++s) {
    std::printf("  %-16s %-10s %14.6g %8d\n", scene.surfaces[s].name.c_str(),
                scene.materials[scene.surfaces[s].material].name.c_str(), surface_area[s],
                surface_patches[s]);
    total += surface_area[s];
  }
  std::printf("\nemitters:");
  int emitters = 0;
  for (const auto& s : scene.surfaces) {
    if (scene.materials[s.material].emits()) {
      std::printf(" %s", s.name.c_str());
      ++emitters;
    }
  }
  std::printf("%s\n", emitters == 0 ? " none" : "");
  const auto [lo, hi] = scene.bounds();
  std::printf("total area: %.10g\n", total);
  std::printf("bounding box: (%g, %g, %g) - (%g, %g, %g)\n", lo.x(), lo.y(), lo.z(), hi.x(),
              hi.y(), hi.z());

  double amin = 1e300, amax = 0.0;
  for (const auto& p : mesh.patches) {
    amin = std::min(amin, p.area);
    amax = std::max(amax, p.area);
  }
  const double amean = total / std::max<size_t>(1, mesh.patches.size());
  std::printf("\nmeshing: max edge %.6g\n", mesh.max_edge);
  std::printf("patches: %d (%zu vertices)\n", mesh.size(), mesh.vertices.size());
  std::printf("patch area: min %.6g  mean %.6g  max %.6g  max/min %.3g\n", amin, amean, amax,
              amax / amin);
  return 0;
}

}  // namespace lambert
