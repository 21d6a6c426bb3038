#include "geometry/render.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"

namespace lambert {
namespace {

// Radiosity B (W/m^2) carried along a camera ray, or nullopt-like `hit = false`.
struct Sample {
  Eigen::Vector3d B = Eigen::Vector3d::Zero();
  bool hit = false;
};

Sample trace(const PatchMesh& mesh, const Bvh& bvh, const Eigen::Vector3d& eye,
             const Eigen::Vector3d& dir, const Eigen::MatrixX3d& patch_B,
             const VertexField& vertices, bool flat, double wire_angle) {
  Sample s;
  const RayHit h = bvh.intersect(eye.cast<float>(), dir.cast<float>());
  if (h.patch < 0) return s;
  s.hit = true;
  const Patch& p = mesh.patches[h.patch];
  if (p.normal.dot(dir) >= 0) return s;  // back face: no radiosity leaves it
  if (wire_angle > 0) {
    // Distance from the hit to the patch's boundary against the pixel's footprint there.
    const Eigen::Vector3d x = eye + h.t * dir;
    const double cosine = std::max(0.25, -p.normal.dot(dir.normalized()));
    const double width = 0.5 * wire_angle * h.t * dir.norm() / cosine;
    for (int k = 0; k < p.vertex_count; ++k) {
      const Eigen::Vector3d& a = mesh.vertices[p.vertices[k]];
      const Eigen::Vector3d& b = mesh.vertices[p.vertices[(k + 1) % p.vertex_count]];
      const double t = std::clamp((x - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      if ((a + t * (b - a) - x).norm() < width) return s;  // on an edge: black
    }
  }
  if (flat) {
    s.B = patch_B.row(h.patch).transpose();
    return s;
  }
  const Eigen::Vector3d x = eye + h.t * dir;
  const auto w = patch_weights(mesh, h.patch, x);
  const auto& c = vertices.patch_corners[h.patch];
  for (int k = 0; k < p.vertex_count; ++k) s.B += w[k] * vertices.values.row(c[k]).transpose();
  return s;
}

}  // namespace

Image render(const PatchMesh& mesh, const Bvh& bvh, const Camera& camera,
             const Eigen::MatrixX3d& patch_B, const VertexField& vertices,
             const RenderSettings& options, RenderStats* stats) {
  LAMBERT_CHECK(camera.width > 0 && camera.height > 0, "render: empty image");
  LAMBERT_CHECK(options.antialias >= 1, "render: antialias must be >= 1");
  LAMBERT_CHECK(patch_B.rows() == mesh.size(), "render: radiosity size does not match the mesh");
  LAMBERT_CHECK(options.flat || (vertices.patch_corners.size() == mesh.patches.size() &&
                                 vertices.values.rows() == vertices.size()),
                "render: vertex field does not match the mesh");
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
  const double inv_pi = 1.0 / M_PI;
  const double inv_samples = 1.0 / (K * K);
  std::unique_ptr<Progress> progress;
  if (options.progress) progress = std::make_unique<Progress>("render", img.height, "rays");

  parallel_for(img.height, 1, options.threads, [&](std::int64_t y0, std::int64_t y1) {
    for (std::int64_t y = y0; y < y1; ++y) {
      for (int x = 0; x < img.width; ++x) {
        const std::uint64_t pixel = static_cast<std::uint64_t>(y) * img.width + x;
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        int hits = 0;
        Rng rng(hash_keys(options.seed, pixel, 0x72656e646572ull));  // "render"
        for (int sy = 0; sy < K; ++sy) {
          for (int sx = 0; sx < K; ++sx) {
            // Stratum centre for K = 1; jittered inside the stratum otherwise.
            const double jx = K == 1 ? 0.5 : rng.uniform();
            const double jy = K == 1 ? 0.5 : rng.uniform();
            const double px = x + (sx + jx) / K;
            const double py = static_cast<double>(y) + (sy + jy) / K;
            const Sample s = trace(mesh, bvh, camera.eye, camera.ray_direction(px, py), patch_B,
                                   vertices, options.flat, wire_angle);
            sum += s.B;
            hits += s.hit ? 1 : 0;
          }
        }
        const Eigen::Vector3d L = sum * (inv_samples * inv_pi);
        const size_t k = static_cast<size_t>(pixel);
        for (int c = 0; c < 3; ++c) img.rgb[3 * k + c] = static_cast<float>(L[c]);
        img.alpha[k] = static_cast<float>(hits * inv_samples);
      }
      if (progress) progress->advance(1, static_cast<std::int64_t>(img.width) * K * K);
    }
  });
  if (progress) progress->finish();
  if (stats) {
    stats->rays = static_cast<std::int64_t>(img.width) * img.height * K * K;
    stats->seconds = timer.seconds();
  }
  return img;
}

}  // namespace lambert
