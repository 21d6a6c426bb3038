#pragma once
// Rendering a radiosity solution: pinhole primary rays through the BVH, each hit shaded with
// its radiance L = B / π (a Lambertian surface of radiosity B has radiance B/π in every
// direction, W m^-2 sr^-1 in the scene's units). Gouraud shading interpolates B from the
// shading vertices of a VertexField (barycentric on triangles, bilinear on quads, from the
// hit point and the patch corners); flat shading uses the patch value. Only the front side
// of a patch leaves radiosity: a hit on a back face is black, a miss is black with coverage 0.
//
// Antialiasing: K x K stratified samples per pixel, each jittered inside its stratum by a
// hash of (seed, pixel, sample), so the image is a pure function of the inputs (deterministic
// for any thread count). Pixel value = mean over samples; alpha = fraction of samples that hit.
// Complexity O(width · height · K²) ray casts; rows are rendered in parallel.
//
// Raytrace shading hands each camera ray's hit to the view pass (raytrace.hpp): specular
// bounces to --specular-depth, Gouraud radiance or a final gather at diffuse hits.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "geometry/media/medium.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/render/camera.hpp"
#include "geometry/render/pixel_direct.hpp"
#include "geometry/render/raytrace.hpp"
#include "geometry/render/vertex_field.hpp"
#include "geometry/visibility/bvh.hpp"
#include "geometry/visibility/daylight.hpp"
#include "geometry/visibility/direct_light.hpp"

namespace lambert {

/// A linear HDR image: RGB radiance and coverage, rows top to bottom.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> rgb;    ///< width * height * 3, linear radiance
  std::vector<float> alpha;  ///< width * height, fraction of samples that hit a surface

  /// Radiance of pixel (x, y) (x right, y down).
  Eigen::Vector3f pixel(int x, int y) const {
    const size_t k = 3 * (static_cast<size_t>(y) * width + x);
    return {rgb[k], rgb[k + 1], rgb[k + 2]};
  }
};

/// How a camera ray's hit is shaded.
enum class Shading {
  Gouraud,   ///< B/π interpolated from the vertex field
  Flat,      ///< B/π of the patch
  Raytrace,  ///< the view pass: specular bounces, Gouraud or final gather at diffuse hits
};

/// A participating medium seen by the camera: each voxel's radiosity B_v = π S_v (S its
/// source radiance: emitted plus in-scattered, W m⁻² sr⁻¹; zero where σt = 0). Along a camera
/// ray the surface's B is dimmed by exp(−τ) to the hit, and voxel v adds
/// B_v exp(−τ before v)(1 − exp(−σt_v ℓ_v)): the exact integral of σt S exp(−τ) for a source
/// constant in each voxel (medium.hpp's walk, no marching step).
struct MediumView {
  const Medium* medium = nullptr;  ///< null: no medium
  Eigen::MatrixX3d voxel_B;        ///< voxels x 3
};

/// Render settings.
struct RenderSettings {
  Shading shading = Shading::Gouraud;
  ViewPassSettings view;  ///< read with Shading::Raytrace
  /// Patch edges drawn black over the shading: a sample whose hit lies within 0.5 pixel
  /// footprints (the pixel's width at the hit's distance, divided by the cosine to the
  /// surface, at least 1/4) of its patch's boundary is black.
  bool wireframe = false;
  int antialias = 2;       ///< K: K x K stratified samples per pixel (1 = pixel centres)
  std::uint64_t seed = 1;  ///< jitter seed (K > 1)
  int threads = 0;         ///< 0 = all cores
  bool progress = true;    ///< draw a progress bar (when stderr is a terminal)
  /// Camera rays through a medium (Gouraud and flat shading; must outlive the render).
  const MediumView* medium = nullptr;
  /// Daylight (Gouraud and flat shading; must outlive the render): samples that miss the
  /// scene see the sky, and every front hit adds its reflected sun light ρ H_sun(x) with one
  /// exact shadow ray (daylight.hpp), so `patch_B` and `vertices` must hold B without the
  /// patches' own sun part (render_scene takes it out).
  const Daylight* daylight = nullptr;
  /// Direct light per pixel (Gouraud shading; must outlive the render): every front hit adds
  /// ρ H_d(x) from its shadow rays (pixel_direct.hpp), so `vertices` must hold B without the
  /// direct part, E + ρ I (render_scene builds it).
  const PixelDirectLight* pixel_direct = nullptr;
};

/// What the render did.
struct RenderStats {
  std::int64_t rays = 0;  ///< every ray cast (camera, specular, gather, shadow)
  double seconds = 0.0;
  int direct_rays = 0;  ///< shadow rays per sample for the direct light per pixel (0: none)
};

/// Renders the mesh as seen by `camera` (its width x height). `patch_B` is N x 3; `vertices`
/// (with values) is used for Gouraud shading and ignored when flat. `direct` (the exact
/// direct light of the mesh's scene) is needed with a final gather only.
/// Thread-safe with respect to its inputs (all const).
Image render(const PatchMesh& mesh, const Bvh& bvh, const Camera& camera,
             const Eigen::MatrixX3d& patch_B, const VertexField& vertices,
             const RenderSettings& options, RenderStats* stats = nullptr,
             const DirectLight* direct = nullptr);

}  // namespace lambert
