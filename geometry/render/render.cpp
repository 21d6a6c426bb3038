#include "geometry/render/render.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"

namespace lambert {
namespace {

// What a camera ray brings back: radiosity B (W/m^2, Gouraud and flat) or radiance L
// (raytrace), and whether it hit anything.
struct Sample {
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
  bool hit = false;
  double t = std::numeric_limits<double>::infinity();  ///< ray parameter of the hit
};

// True when the hit lies within half a pixel footprint of its patch's boundary.
bool on_wire(const PatchMesh& mesh, const Patch& p, const Eigen::Vector3d& eye,
             const Eigen::Vector3d& dir, double t, double wire_angle) {
  const Eigen::Vector3d x = eye + t * dir;
  const double cosine = std::max(0.25, -p.normal.dot(dir.normalized()));
  const double width = 0.5 * wire_angle * t * dir.norm() / cosine;
  for (int k = 0; k < p.vertex_count; ++k) {
    const Eigen::Vector3d& a = mesh.vertices[p.vertices[k]];
    const Eigen::Vector3d& b = mesh.vertices[p.vertices[(k + 1) % p.vertex_count]];
    const double s = std::clamp((x - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    if ((a + s * (b - a) - x).norm() < width) return true;
  }
  return false;
}

// The direct light's sequence of one pixel (keyed by seed and pixel) and the sample's place
// in it: the pixel's samples take consecutive runs of it (pixel_direct.hpp).
struct PixelStream {
  std::uint64_t stream = 0;
  std::int64_t sample = 0;
};

Sample trace(const PatchMesh& mesh, const Bvh& bvh, const Eigen::Vector3d& eye,
             const Eigen::Vector3d& dir, const Eigen::MatrixX3d& patch_B,
             const VertexField& vertices, Shading shading, double wire_angle,
             const ViewTracer* tracer, const Daylight* daylight,
             const PixelDirectLight* pixel_direct, PixelStream direct, std::uint64_t stream,
             std::int64_t& rays) {
  Sample s;
  ++rays;
  const RayHit h = bvh.intersect(eye.cast<float>(), dir.cast<float>());
  if (h.patch < 0) {
    if (daylight) s.value = M_PI * daylight->sky;  // the sky's radiance L, as B = π L
    return s;
  }
  s.hit = true;
  s.t = h.t;
  const Patch& p = mesh.patches[h.patch];
  const bool front = p.normal.dot(dir) < 0;
  if (wire_angle > 0 && (front || tracer) && on_wire(mesh, p, eye, dir, h.t, wire_angle))
    return s;  // on an edge: black
  if (tracer) {
    s.value = tracer->radiance(eye, dir, h, stream, rays);
    return s;
  }
  if (!front) return s;  // back face: no radiosity leaves it
  const Eigen::Vector3d x = eye + h.t * dir;
  s.value = shading == Shading::Flat ? Eigen::Vector3d(patch_B.row(h.patch).transpose())
                                     : field_value(mesh, vertices, h.patch, x);
  if (pixel_direct)
    s.value += p.rho.cwiseProduct(pixel_direct->irradiance(
        bvh, x, p.normal, direct.stream, direct.sample * pixel_direct->rays(), rays));
  if (daylight && daylight->has_sun()) {
    if (p.normal.dot(daylight->sun_direction) < 0.0) ++rays;  // the shadow ray
    s.value += p.rho.cwiseProduct(
        sun_irradiance_at(bvh, *daylight, x, p.normal, kSunRayOffset * mesh.scale));
  }
  return s;
}

// The camera ray's radiosity seen through the medium: the surface's B times exp(-tau) to
// the hit plus every voxel's B_v exp(-tau before)(1 - exp(-sigma_t l)) (render.hpp).
Eigen::Vector3d through_medium(const MediumView& view, const Eigen::Vector3d& eye,
                               const Eigen::Vector3d& dir, const Sample& s) {
  const double norm = dir.norm();
  const Eigen::Vector3d unit = dir / norm;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double tau = 0.0;
  const Medium& m = *view.medium;
  traverse_medium(m, eye, unit, 0.0, s.t * norm, [&](std::int32_t v, double a, double b) {
    const double dtau = m.sigma_t(v) * (b - a);
    sum += std::exp(-tau) * -std::expm1(-dtau) * view.voxel_B.row(v).transpose();
    tau += dtau;
  });
  return std::exp(-tau) * s.value + sum;
}

}  // namespace

Image render(const PatchMesh& mesh, const Bvh& bvh, const Camera& camera,
             const Eigen::MatrixX3d& patch_B, const VertexField& vertices,
             const RenderSettings& options, RenderStats* stats, const DirectLight* direct) {
  LAMBERT_CHECK(camera.width > 0 && camera.height > 0, "render: empty image");
  LAMBERT_CHECK(options.antialias >= 1, "render: antialias must be >= 1");
  LAMBERT_CHECK(patch_B.rows() == mesh.size(), "render: radiosity size does not match the mesh");
  LAMBERT_CHECK(
      !options.medium || (options.shading != Shading::Raytrace &&
                          options.medium->voxel_B.rows() == options.medium->medium->voxels()),
      "render: a medium needs Gouraud or flat shading and one value per voxel");
  LAMBERT_CHECK(!options.daylight || (options.shading != Shading::Raytrace && !options.medium),
                "render: daylight needs Gouraud or flat shading and no medium");
  LAMBERT_CHECK(!options.pixel_direct ||
                    (options.shading == Shading::Gouraud && !options.medium && !options.daylight),
                "render: direct light per pixel needs Gouraud shading, no medium and no daylight");
  const bool flat = options.shading == Shading::Flat;
  const bool gathers = options.shading == Shading::Raytrace && options.view.final_gather > 0;
  LAMBERT_CHECK(flat || gathers ||
                    (vertices.patch_corners.size() == mesh.patches.size() &&
                     vertices.values.rows() == vertices.size()),
                "render: vertex field does not match the mesh");
  std::unique_ptr<ViewTracer> tracer;
  if (options.shading == Shading::Raytrace)
    tracer = std::make_unique<ViewTracer>(mesh, bvh, patch_B, vertices, options.view, direct);
  const Timer timer;
  Image img;
  img.width = camera.width;
  img.height = camera.height;
  img.rgb.assign(static_cast<size_t>(img.width) * img.height * 3, 0.0f);
  img.alpha.assign(static_cast<size_t>(img.width) * img.height, 0.0f);
  const int K = options.antialias;
  // The angle one pixel subtends (radians), 0 without a wireframe.
  const double wire_angle =
      options.wireframe ? 2.0 * std::tan(camera.vfov_degrees * M_PI / 360.0) / camera.height : 0.0;
  const double inv_samples = 1.0 / (K * K);
  // Gouraud and flat samples carry B, raytraced ones L: pixel = mean of B/π, or of L.
  const double to_radiance = tracer ? inv_samples : inv_samples * (1.0 / M_PI);
  std::vector<std::int64_t> row_rays(static_cast<size_t>(img.height), 0);
  std::unique_ptr<Progress> progress;
  if (options.progress) progress = std::make_unique<Progress>("render", img.height, "rays");

  parallel_for(img.height, 1, options.threads, [&](std::int64_t y0, std::int64_t y1) {
    for (std::int64_t y = y0; y < y1; ++y) {
      for (int x = 0; x < img.width; ++x) {
        const std::uint64_t pixel = static_cast<std::uint64_t>(y) * img.width + x;
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        int hits = 0;
        Rng rng(hash_keys(options.seed, pixel, 0x72656e646572ull));  // "render"
        const std::uint64_t direct_stream =
            hash_keys(options.seed, pixel, 0x646972656374ull);  // "direct"
        for (int sy = 0; sy < K; ++sy) {
          for (int sx = 0; sx < K; ++sx) {
            // Stratum centre for K = 1; jittered inside the stratum otherwise.
            const double jx = K == 1 ? 0.5 : rng.uniform();
            const double jy = K == 1 ? 0.5 : rng.uniform();
            const double px = x + (sx + jx) / K;
            const double py = static_cast<double>(y) + (sy + jy) / K;
            const std::uint64_t stream =
                hash_keys(options.seed ^ 0x76696577ull, pixel, sy * K + sx);  // "view"
            const Sample s =
                trace(mesh, bvh, camera.eye, camera.ray_direction(px, py), patch_B, vertices,
                      options.shading, wire_angle, tracer.get(), options.daylight,
                      options.pixel_direct, {direct_stream, sy * K + sx}, stream, row_rays[y]);
            sum += options.medium ? through_medium(*options.medium, camera.eye,
                                                   camera.ray_direction(px, py), s)
                                  : s.value;
            hits += s.hit ? 1 : 0;
          }
        }
        const Eigen::Vector3d L = sum * to_radiance;
        const size_t k = static_cast<size_t>(pixel);
        for (int c = 0; c < 3; ++c) img.rgb[3 * k + c] = static_cast<float>(L[c]);
        img.alpha[k] = static_cast<float>(hits * inv_samples);
      }
      if (progress) progress->advance(1, row_rays[y]);
    }
  });
  if (progress) progress->finish();
  if (stats) {
    stats->rays = 0;
    for (std::int64_t r : row_rays) stats->rays += r;
    stats->seconds = timer.seconds();
  }
  return img;
}

}  // namespace lambert
