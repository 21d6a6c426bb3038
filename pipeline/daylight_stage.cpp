#include "pipeline/daylight_stage.hpp"

#include <cstdio>
#include <string>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/sampling.hpp"
#include "geometry/visibility/daylight.hpp"
#include "pipeline/problem.hpp"

namespace lambert {
namespace {

Eigen::MatrixX3d times_rho(const PatchMesh& mesh, const Eigen::MatrixX3d& H) {
  Eigen::MatrixX3d out = Eigen::MatrixX3d::Zero(mesh.size(), 3);
  if (H.rows() == 0) return out;
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    out.row(i) = mesh.patches[i].rho.cwiseProduct(H.row(i).transpose()).transpose();
  return out;
}

Eigen::Vector3d power(const PatchMesh& mesh, const Eigen::MatrixX3d& H) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (std::int32_t i = 0; i < mesh.size(); ++i) p += mesh.patches[i].area * H.row(i).transpose();
  return p;
}

Json rgb(const Eigen::Vector3d& v) { return Json::array({v[0], v[1], v[2]}); }

}  // namespace

Eigen::MatrixX3d DaylightSources::reflected(const PatchMesh& mesh) const {
  Eigen::MatrixX3d out = times_rho(mesh, sky);
  if (sun.rows() > 0) out += times_rho(mesh, sun);
  return out;
}

Eigen::MatrixX3d DaylightSources::reflected_sun(const PatchMesh& mesh) const {
  return times_rho(mesh, sun);
}

Eigen::MatrixX3d sun_patch_part(const LoadedScene& scene, std::uint64_t seed, int threads) {
  const Daylight& light = scene.scene.daylight;
  if (!light.has_sun()) return Eigen::MatrixX3d::Zero(scene.mesh.size(), 3);
  const std::uint64_t key = hash_keys(mesh_hash(scene.mesh), seed);  // O(N), no rays
  if (!scene.sun_part || scene.sun_part_key != key) {
    scene.sun_part = std::make_shared<const Eigen::MatrixX3d>(
        sun_patch_irradiance(scene.mesh, scene_bvh(scene, threads), light, seed, threads));
    scene.sun_part_key = key;
  }
  return *scene.sun_part;
}

DaylightSources daylight_sources(const LoadedScene& scene, const FormFactors& F, std::uint64_t seed,
                                 int threads) {
  if (!scene.scene.daylight.any()) return {};
  return daylight_sources(scene.scene.daylight, scene.mesh, F.F, F.specular_continued,
                          sun_patch_part(scene, seed, threads));
}

DaylightSources daylight_sources(const Daylight& light, const PatchMesh& mesh, const Bvh& bvh,
                                 const SparseRowMatrix& F, const Eigen::VectorXd& continued,
                                 std::uint64_t seed, int threads) {
  if (!light.any()) return {};
  return daylight_sources(light, mesh, F, continued,
                          sun_patch_irradiance(mesh, bvh, light, seed, threads));
}

DaylightSources daylight_sources(const Daylight& light, const PatchMesh& mesh,
                                 const SparseRowMatrix& F, const Eigen::VectorXd& continued,
                                 Eigen::MatrixX3d sun) {
  DaylightSources d;
  if (!light.any()) return d;
  if (mesh.has_specular())
    throw UsageError(
        "--sky and --sun do not follow light through mirrors and glass yet, and this scene "
        "has specular surfaces");
  d.sky = Eigen::MatrixX3d::Zero(mesh.size(), 3);
  if (light.has_sky()) {
    const Eigen::VectorXd s = escape_fractions(F, continued, mesh.size());
    for (std::int32_t i = 0; i < mesh.size(); ++i) d.sky.row(i) = M_PI * s[i] * light.sky;
    d.sky_power = power(mesh, d.sky);
    if (!(d.sky_power.maxCoeff() > 0.0))
      log_warn("--sky: no patch sees the sky (the scene is closed): it adds no light");
  }
  d.sun = std::move(sun);
  if (light.has_sun()) {
    d.sun_power = power(mesh, d.sun);
    if (!(d.sun_power.maxCoeff() > 0.0))
      log_warn(
          "--sun: no patch is lit by the sun (each faces away from it or lies in shadow): "
          "it adds no light");
  }
  char line[200];
  std::snprintf(line, sizeof line,
                "daylight: the sky brings %.4g W and the sun %.4g W to the patches (green)",
                d.sky_power[1], d.sun_power[1]);
  log_info(line);
  return d;
}

RadiosityProblem make_lit_problem(const LoadedScene& scene, const FormFactors& F,
                                  std::uint64_t seed, int threads, DaylightSources* sources) {
  RadiosityProblem problem = make_problem(scene.mesh, F);
  DaylightSources d = daylight_sources(scene, F, seed, threads);
  if (d.sky.rows() > 0) problem.emission.topRows(scene.mesh.size()) += d.reflected(scene.mesh);
  if (sources) *sources = std::move(d);
  return problem;
}

std::string daylight_settings_text(const Daylight& light) {
  std::string out;
  char buf[200];
  if (light.has_sky()) {
    std::snprintf(buf, sizeof buf, " sky=%.9g,%.9g,%.9g", light.sky[0], light.sky[1], light.sky[2]);
    out += buf;
  }
  if (light.has_sun()) {
    const Eigen::Vector3d& d = light.sun_direction;
    const Eigen::Vector3d& s = light.sun_irradiance;
    std::snprintf(buf, sizeof buf, " sun=%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", d[0], d[1], d[2], s[0],
                  s[1], s[2]);
    out += buf;
  }
  return out;
}

Json daylight_json(const Daylight& light, const DaylightSources& sources) {
  if (!light.any()) return Json();
  Json j = Json::object();
  if (light.has_sky()) {
    j["sky_radiance"] = rgb(light.sky);
    j["sky_power"] = rgb(sources.sky_power);
  }
  if (light.has_sun()) {
    j["sun_direction"] = rgb(light.sun_direction);
    j["sun_irradiance"] = rgb(light.sun_irradiance);
    j["sun_power"] = rgb(sources.sun_power);
  }
  return j;
}

}  // namespace lambert
