#include "geometry/render/raytrace.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>

#include "core/sampling.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/reference.hpp"
#include "geometry/mesh/adapt.hpp"
#include "geometry/render/render.hpp"

namespace lambert {
namespace {

Material diffuse(const std::string& name, double rho, const Eigen::Vector3d& e = {0, 0, 0}) {
  return Material(name, Eigen::Vector3d::Constant(rho), e);
}

Material glass(const Eigen::Vector3d& tf) {
  Material m("glass", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  m.specular.dielectric = true;
  m.specular.ior = 1.5;
  m.specular.transmission = tf;
  return m;
}

Material mirror(const Eigen::Vector3d& rho_s) {
  Material m("mirror", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  m.specular.reflectance = rho_s;
  return m;
}

// An axis-aligned rectangle in the plane z = `z`, facing +z (`up`) or -z.
void add_rect(Scene& s, const std::string& name, const Material& m, double x0, double x1, double y0,
              double y1, double z, bool up) {
  std::vector<Eigen::Vector3d> c = {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}};
  if (!up) std::swap(c[1], c[3]);
  add_polygon(s, name, m, c);
}

// A closed box [lo, hi], faces wound to point outward, on one surface.
void add_outward_box(Scene& s, const std::string& name, const Material& m,
                     const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const auto p = [&](int i) {
    return Eigen::Vector3d(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                           i & 4 ? hi.z() : lo.z());
  };
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) add_polygon(s, name, m, {p(q[0]), p(q[1]), p(q[2]), p(q[3])});
}

Camera camera(const Eigen::Vector3d& eye, const Eigen::Vector3d& at, double fov, int w, int h) {
  Camera c;
  c.eye = eye;
  c.look_at = at;
  c.up = Eigen::Vector3d::UnitY();
  c.vfov_degrees = fov;
  c.width = w;
  c.height = h;
  c.defined = true;
  return c;
}

// Patch values E (the emission of each patch): B = E where nothing reflects diffusely.
Eigen::MatrixX3d emission_of(const PatchMesh& mesh) {
  Eigen::MatrixX3d B(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i) B.row(i) = mesh.patches[i].emission.transpose();
  return B;
}

RenderSettings raytraced(int depth, int gather = 0) {
  RenderSettings o;
  o.shading = Shading::Raytrace;
  o.view.specular_depth = depth;
  o.view.final_gather = gather;
  o.antialias = 1;
  o.progress = false;
  return o;
}

// The inside of the unit cube (no face hides another) with walls and floor of ρ = 0.5 and
// an emitting ceiling (z = 1, ρ = 0, E = 4); or every face the same material `all`.
Scene cube_of(const Material* all = nullptr) {
  Scene s;
  const Scene cube = unit_cube();
  for (const Face& f : cube.faces) {
    std::vector<Eigen::Vector3d> c;
    for (auto v : f.vertices) c.push_back(cube.vertices[v]);
    const bool ceiling = (c[1] - c[0]).cross(c[2] - c[1]).z() < 0;
    const Material m = all ? *all : ceiling ? diffuse("light", 0.0, {4, 4, 4}) : diffuse("w", 0.5);
    add_polygon(s, cube.surfaces[f.surface].name, m, c);
  }
  return s;
}

}  // namespace

TEST(ViewPass, RaytraceOnADiffuseSceneEqualsGouraud) {
  const PatchMesh mesh = mesh_scene(cube_of(), {0.2, 0});
  const Bvh bvh(mesh);
  // A smooth, non-uniform B so that the interpolation matters.
  Eigen::MatrixX3d B(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Eigen::Vector3d& c = mesh.patches[i].centroid;
    B.row(i) << 1 + c.x(), 2 + c.y() * c.z(), 0.5 + c.z();
  }
  const VertexField field = interpolate_to_vertices(mesh, B);
  const Camera cam = camera({0.5, 0.2, 0.5}, {0.4, 0.9, 0.6}, 80, 40, 30);
  RenderSettings gouraud;
  gouraud.antialias = 2;
  gouraud.progress = false;
  RenderSettings traced = gouraud;
  traced.shading = Shading::Raytrace;
  const Image a = render(mesh, bvh, cam, B, field, gouraud);
  const Image b = render(mesh, bvh, cam, B, field, traced);
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  EXPECT_EQ(a.alpha, b.alpha);
  for (size_t k = 0; k < a.rgb.size(); ++k) {
    // Same rays, same interpolation; only the order of the 1/π and 1/K² products differs
    // (a few double ulps, 1e-15). Each float store rounds to half an ulp, 2^-24 relative,
    // so the two floats differ by at most one ulp: 2^-23 = 1.2e-7 relative.
    EXPECT_NEAR(a.rgb[k], b.rgb[k], 1.2e-7 * std::abs(a.rgb[k])) << k;
  }
}

TEST(ViewPass, GlassSlabTransmitsTheSumOfInternalReflections) {
  // A uniform emitter (ρ = 0: B = E exactly) at z = 0 seen through a glass slab (ior 1.5,
  // 4 x 4 x 0.2) at z in [1, 1.2] by a camera at z = 5 looking straight down its axis.
  const Eigen::Vector3d E(1, 2, 3), tf(1.0, 0.5, 0.25);
  Scene s;
  add_rect(s, "wall", diffuse("wall", 0.0, E), -5, 5, -5, 5, 0.0, true);
  add_outward_box(s, "slab", glass(tf), {-2, -2, 1.0}, {2, 2, 1.2});
  const PatchMesh mesh = mesh_scene(s, {});
  const Bvh bvh(mesh);
  const Eigen::MatrixX3d B = emission_of(mesh);
  const VertexField field = interpolate_to_vertices(mesh, B);
  // One pixel, antialias 1: the ray through its centre is the view axis, (0, 0, -1) exactly,
  // so every interface is met at normal incidence and refraction keeps the direction.
  const Camera cam = camera({0, 0, 5}, {0, 0, 0}, 10, 1, 1);
  const double R = std::pow((1.5 - 1.0) / (1.5 + 1.0), 2);  // 0.04
  for (int depth : {0, 1, 2, 3, 4, 5, 8}) {
    // Entering (bounce 1) and leaving (bounce 2) pass (1 − R)² Tf (Tf once: the ray enters
    // once); each round trip inside adds two reflections (R²) and two bounces, and light
    // leaving through the top escapes (nothing above). Paths with k round trips need 2 + 2k
    // bounces: T_D = (1 − R)² Σ_{k=0..K} R^{2k}, K = floor((D − 2) / 2), 0 for D < 2.
    double T = 0.0;
    for (int k = 0; 2 + 2 * k <= depth; ++k) T += std::pow(1 - R, 2) * std::pow(R, 2 * k);
    const Image img = render(mesh, bvh, cam, B, field, raytraced(depth));
    for (int c = 0; c < 3; ++c) {
      // Doubles summed over ≤ 2^D branches (1e-15), stored as float: 2^-24 relative.
      EXPECT_NEAR(img.pixel(0, 0)[c], T * tf[c] * E[c] / M_PI, 1e-7 * E[c]) << depth;
    }
    if (depth == 8) {
      // The whole series (1 − R)² / (1 − R²) is missed by R^{2(K+1)} = R^8 = 6.6e-12 relative
      // (K = 3), far below the float store's 6e-8.
      const double T_inf = std::pow(1 - R, 2) / (1 - R * R);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(img.pixel(0, 0)[c], T_inf * tf[c] * E[c] / M_PI, 1e-7 * E[c]);
    }
  }
}

TEST(ViewPass, MirrorShowsItsOwnRadiancePlusTheMirroredCameraViewTimesRhoS) {
  // A wall at z = 3 facing the mirror (z = 0) with a smooth B; the camera at z = 1 looks at
  // the mirror, the mirrored camera (z = -1) at the wall with the mirror taken away.
  // The mirror is also diffuse (ρ 0.3 + ρ_s ≤ 1) with a uniform B_m of its own.
  const Eigen::Vector3d rho_s(0.6, 0.5, 0.3), B_m(0.7, 0.8, 0.9);
  Scene with, without;
  for (Scene* s : {&with, &without})
    add_rect(*s, "wall", diffuse("wall", 0.5), -10, 10, -10, 10, 3.0, false);
  Material shiny = mirror(rho_s);
  shiny.rho = Eigen::Vector3d::Constant(0.3);
  add_rect(with, "mirror", shiny, -3, 3, -3, 3, 0.0, true);
  const PatchMesh mesh = mesh_scene(with, {1.0, 0});
  const PatchMesh bare = mesh_scene(without, {1.0, 0});
  Eigen::MatrixX3d B = Eigen::MatrixX3d::Zero(mesh.size(), 3);
  for (std::int32_t i = 0; i < bare.size(); ++i) {
    ASSERT_EQ(mesh.patches[i].centroid, bare.patches[i].centroid);  // the same wall patches
    const Eigen::Vector3d& c = bare.patches[i].centroid;
    B.row(i) << 2 + 0.1 * c.x(), 2 + 0.05 * c.y(), 2 + 0.1 * c.x() - 0.05 * c.y();
  }
  for (std::int32_t i = bare.size(); i < mesh.size(); ++i) B.row(i) = B_m.transpose();
  const Eigen::MatrixX3d B_bare = B.topRows(bare.size());
  const VertexField field = interpolate_to_vertices(mesh, B, VertexInterpolation::AreaWeighted);
  const VertexField field_bare =
      interpolate_to_vertices(bare, B_bare, VertexInterpolation::AreaWeighted);
  const Bvh bvh(mesh), bvh_bare(bare);
  const int W = 32, H = 24;
  const Image seen =
      render(mesh, bvh, camera({0.3, -0.2, 1}, {0.5, 0.1, 0}, 40, W, H), B, field, raytraced(8));
  RenderSettings gouraud;
  gouraud.antialias = 1;
  gouraud.progress = false;
  const Image direct = render(bare, bvh_bare, camera({0.3, -0.2, -1}, {0.5, 0.1, 0}, 40, W, H),
                              B_bare, field_bare, gouraud);
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      // Mirroring flips the camera's right vector (r' = -M r for M = diag(1, 1, -1)), so
      // pixel centre x + 0.5 maps to W - x - 0.5: pixel W - 1 - x.
      const Eigen::Vector3f a = seen.pixel(x, y), b = direct.pixel(W - 1 - x, y);
      ASSERT_GT(b.minCoeff(), 0.5f / M_PI);  // every ray reaches the wall (B >= 1)
      for (int c = 0; c < 3; ++c) {
        // The reflected ray starts 1e-6 × scene size (≈ 3e-5) off the mirror, and its float
        // hit is rounded by ~1e-7 × 3: the wall point moves by < 1e-4; B's slope is ≤ 0.15
        // per unit on B ≥ 1, so L moves by < 2e-5 relative; 1e-4 leaves a margin.
        // L = B_m/π + ρ_s L_reflected (B_m uniform: its Gouraud value is exact).
        EXPECT_NEAR(a[c], B_m[c] / M_PI + rho_s[c] * b[c], 1e-4 * b[c]) << x << "," << y;
      }
    }
  }
}

TEST(FinalGather, DirectLightWithNothingBlockingIsTheExactFactorTimesE) {
  // A 2 x 1 emitter (ρ 0) at height 1 over a large floor (ρ 0.5), nothing else: gather rays
  // escape or hit the emitter, whose B − E is 0, so B_fg = ρ E F_{dx→emitter} exactly.
  const Eigen::Vector3d E(3, 2, 1);
  Scene s;
  add_rect(s, "floor", diffuse("floor", 0.5), -4, 4, -4, 4, 0.0, true);
  add_rect(s, "light", diffuse("light", 0.0, E), 0, 2, 0, 1, 1.0, false);
  const PatchMesh mesh = mesh_scene(s, {});
  const Bvh bvh(mesh);
  const Eigen::MatrixX3d B = emission_of(mesh);
  ViewPassSettings vs;
  vs.final_gather = 16;
  const DirectLight light(s);
  const ViewTracer tracer(mesh, bvh, B, VertexField{}, vs, &light);
  // Howell B-3: a point under a corner of a parallel a x b rectangle at height c,
  // F = 1/(2π) [A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²))], A = a/c, B = b/c.
  const auto corner = [](double a, double b) {
    const double A2 = 1 + a * a, B2 = 1 + b * b;
    return (a / std::sqrt(A2) * std::atan(b / std::sqrt(A2)) +
            b / std::sqrt(B2) * std::atan(a / std::sqrt(B2))) /
           (2 * M_PI);
  };
  std::int64_t rays = 0;
  // Under the corner (0, 0); and under (0.5, 0.25), splitting the light into four rectangles.
  const double F0 = corner(2, 1);
  const double F1 = corner(0.5, 0.25) + corner(1.5, 0.25) + corner(0.5, 0.75) + corner(1.5, 0.75);
  const std::pair<Eigen::Vector3d, double> cases[] = {{{0, 0, 0}, F0}, {{0.5, 0.25, 0}, F1}};
  for (const auto& [x, F] : cases) {
    const Eigen::Vector3d b = tracer.gathered_radiosity(x, 0, 7, rays);
    // Exact contour integral in doubles: ~1e-15 relative; 1e-12 is rounding with a margin.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[c], 0.5 * E[c] * F, 1e-12 * E[c]);
  }
  EXPECT_EQ(rays, 2 * 16);
}

TEST(FinalGather, GatherRaysReadTheFullRadiosityAfterAMirror) {
  // An emitting floor (E = 1, ρ = 0.5, given B = 2) under a mirror ceiling (ρ_s = 0.8) at
  // height 1: every gather ray goes up, is reflected and reads the floor's full B (E
  // included: light via a mirror is not in H_d). H_d = 0 (the floor's plane holds x), so
  // B_fg = E + ρ ρ_s B = 1 + 0.5 · 0.8 · 2 = 1.8; reading B − E would give 1.4.
  Scene s;
  add_rect(s, "floor", diffuse("floor", 0.5, {1, 1, 1}), -2000, 2000, -2000, 2000, 0.0, true);
  add_rect(s, "mirror", mirror({0.8, 0.8, 0.8}), -1000, 1000, -1000, 1000, 1.0, false);
  const PatchMesh mesh = mesh_scene(s, {});
  const Bvh bvh(mesh);
  Eigen::MatrixX3d B = Eigen::MatrixX3d::Zero(mesh.size(), 3);
  B.row(0).setConstant(2.0);
  const DirectLight light(s);
  ViewPassSettings vs;
  vs.final_gather = 32;
  const ViewTracer tracer(mesh, bvh, B, VertexField{}, vs, &light);
  std::int64_t rays = 0;
  const Eigen::Vector3d b = tracer.gathered_radiosity({0.3, 0.2, 0.0}, 0, 3, rays);
  // Rays escape past the mirror's edge (tan θ > 1000) with cosine-weighted probability
  // 1 / (1 + 10⁶) = 1e-6, each losing 0.4 · 2 / 32; 1e-6 bounds it with room.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[c], 1.8, 1e-6);
  EXPECT_EQ(rays, 2 * 32);  // up to the mirror, down to the floor
  // With no specular bounce allowed the mirror ends every gather ray.
  vs.specular_depth = 0;
  const ViewTracer flat_tracer(mesh, bvh, B, VertexField{}, vs, &light);
  EXPECT_NEAR(flat_tracer.gathered_radiosity({0.3, 0.2, 0.0}, 0, 3, rays)[0], 1.0, 1e-12);
}

TEST(FinalGather, FurnaceIsExactForAnyRayCount) {
  // Every face of the closed unit cube emits E = 1 and reflects ρ = 0.5: B = E / (1 − ρ) = 2.
  // At any point H_d = E Σ F = 1 (the five other faces enclose it) and every gather ray
  // reads B − E = 1, so B_fg = 1 + 0.5 (1 + 1) = 2 with no variance.
  const Material furnace = diffuse("w", 0.5, {1, 1, 1});
  const Scene s = cube_of(&furnace);
  const PatchMesh mesh = mesh_scene(s, {0.5, 0});
  const Bvh bvh(mesh);
  const Eigen::MatrixX3d B = Eigen::MatrixX3d::Constant(mesh.size(), 3, 2.0);
  const DirectLight light(s);
  for (int n : {1, 7, 64}) {
    ViewPassSettings vs;
    vs.final_gather = n;
    const ViewTracer tracer(mesh, bvh, B, VertexField{}, vs, &light);
    std::int64_t rays = 0;
    for (std::int32_t i = 0; i < mesh.size(); i += 5) {
      const Eigen::Vector3d b = tracer.gathered_radiosity(mesh.patches[i].centroid, i, i, rays);
      // H_d: five exact contour integrals summing to 1 within 1e-14; H_i exact.
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(b[c], 2.0, 1e-12) << n << " " << i;
    }
  }
}

TEST(FinalGatherSlow, ConvergesToTheRadiositySolutionOverAPatch) {
  // The lit cube without blockers: F by the unoccluded quadrature (~1e-8 per entry), B by a
  // dense solve of (I − ρF) B = E. Over patch i, the final gather's expectation at x is
  // E_i + ρ_i (Σ_e E_e F_{x→e} + Σ_j (B_j − E_j) F_{x→j}); its mean over x uniform on i is
  // E_i + ρ_i Σ_j F_ij B_j = B_i (the patch's own equation).
  const Scene s = cube_of();
  const PatchMesh mesh = mesh_scene(s, {0.5, 0});  // 2 x 2 patches a face: 576 quadratures
  const Bvh bvh(mesh);
  const FormFactors ff = unoccluded_quadrature(mesh, 0);
  const Eigen::MatrixXd F(ff.F);
  const std::int32_t n = mesh.size();
  Eigen::MatrixX3d B(n, 3), E(n, 3);
  for (int c = 0; c < 3; ++c) {
    Eigen::MatrixXd K = Eigen::MatrixXd::Identity(n, n);
    for (std::int32_t i = 0; i < n; ++i) {
      K.row(i) -= mesh.patches[i].rho[c] * F.row(i);
      E(i, c) = mesh.patches[i].emission[c];
    }
    B.col(c) = K.partialPivLu().solve(E.col(c));
  }
  const DirectLight light(s);
  // A floor patch (z = 0): [0, 0.5]².
  std::int32_t floor = -1;
  for (std::int32_t i = 0; i < n; ++i) {
    const Patch& p = mesh.patches[i];
    if (p.normal.z() > 0.5 && std::abs(p.centroid.x() - 0.25) < 1e-9 &&
        std::abs(p.centroid.y() - 0.25) < 1e-9)
      floor = i;
  }
  ASSERT_GE(floor, 0);
  const Patch& p = mesh.patches[floor];
  const auto corners = mesh.corners(floor);
  ASSERT_EQ(p.vertex_count, 4);
  double sd_first = 0.0;
  for (int rays_per_point : {4, 64}) {
    ViewPassSettings vs;
    vs.final_gather = rays_per_point;
    const ViewTracer tracer(mesh, bvh, B, VertexField{}, vs, &light);
    // M = 16 x 16 jittered points on the (square) patch, each with its own stream.
    const int m = 16;
    double sum = 0.0, sum2 = 0.0;
    std::int64_t rays = 0;
    Rng rng(hash_keys(5, rays_per_point));
    for (int a = 0; a < m; ++a) {
      for (int b = 0; b < m; ++b) {
        const double u = (a + rng.uniform()) / m, v = (b + rng.uniform()) / m;
        const Eigen::Vector3d x = (1 - u) * (1 - v) * corners[0] + u * (1 - v) * corners[1] +
                                  u * v * corners[2] + (1 - u) * v * corners[3];
        const double g = tracer.gathered_radiosity(x, floor, hash_keys(9, a, b), rays)[0];
        sum += g;
        sum2 += g * g;
      }
    }
    const double M = m * m, mean = sum / M;
    const double sd = std::sqrt(std::max(0.0, (sum2 - M * mean * mean) / (M - 1)));
    // σ̂/√M treats the stratified points as independent, which over-states the error of a
    // stratified mean; 4 σ̂/√M plus the quadrature's F error (Σ_j |ΔF_ij| B_j ≤ 24 · 1e-8 · 4)
    // bounds the difference to B_i with a wide margin.
    EXPECT_NEAR(mean, B(floor, 0), 4 * sd / std::sqrt(M) + 1e-5)
        << "N = " << rays_per_point << ", sd " << sd;

    // The gather noise alone: R = 64 streams at the patch's centroid.
    const int R = 64;
    double s1 = 0.0, s2 = 0.0;
    for (int r = 0; r < R; ++r) {
      const double g = tracer.gathered_radiosity(p.centroid, floor, hash_keys(11, r), rays)[0];
      s1 += g;
      s2 += g * g;
    }
    const double noise = std::sqrt(std::max(0.0, (s2 - s1 * s1 / R) / (R - 1)));
    if (rays_per_point == 4) {
      sd_first = noise;
      EXPECT_GT(noise, 0.0);
    } else {
      // Independent rays give σ ∝ N^-1/2 (a quarter for 16 times the rays), the lattice at
      // least that; σ̂ from 64 replicates is within ±9 % (1/√(2 · 63)): below half is safe.
      EXPECT_LT(noise, 0.5 * sd_first) << "N = 4: " << sd_first << ", N = 64: " << noise;
    }
  }
}

// On a coarse mesh of the lit cube (smooth, unshadowed field) the final-gather image and
// the Gouraud image differ by less than the meshing error estimate of the solution: the
// jump estimate of adapt.hpp, Σ e_i / Σ A_i, the area-mean error of the piecewise-constant
// B (Gouraud interpolates it, final gather recomputes the radiosity at each point, so both
// lie within the constant's error of the true field). The difference is measured as the
// mean over pixels of |L_fg − L_gouraud| · π (radiosity units); the gather's own noise
// (N = 256 rays per hit: ρ σ_g / √N, σ_g the spread of the B − E values the rays read, the
// walls' reflected radiosity, below 1 here) adds at most ~0.5 / 16 = 0.03 to it. Measured:
// difference 0.083, estimate 0.117 (seeded: deterministic).
TEST(FinalGatherSlow, DiffersFromGouraudByLessThanTheMeshingErrorEstimate) {
  const Scene s = cube_of();
  const PatchMesh mesh = mesh_scene(s, {0.5, 0});
  const Bvh bvh(mesh);
  const FormFactors ff = unoccluded_quadrature(mesh, 0);
  const Eigen::MatrixXd F(ff.F);
  const std::int32_t n = mesh.size();
  Eigen::MatrixX3d B(n, 3);
  for (int c = 0; c < 3; ++c) {
    Eigen::MatrixXd K = Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd E(n);
    for (std::int32_t i = 0; i < n; ++i) {
      K.row(i) -= mesh.patches[i].rho[c] * F.row(i);
      E[i] = mesh.patches[i].emission[c];
    }
    B.col(c) = K.partialPivLu().solve(E);
  }
  const std::vector<double> e = patch_errors(mesh, B);
  double area = 0.0, err = 0.0;
  for (std::int32_t i = 0; i < n; ++i) area += mesh.patches[i].area, err += e[i];
  const double estimate = err / area;
  ASSERT_GT(estimate, 0.0);
  const VertexField field = interpolate_to_vertices(mesh, B, VertexInterpolation::Conservative);
  // Looking down at the floor and the lower walls from inside, below the emitting ceiling.
  const Camera cam = camera({0.5, 0.5, 0.9}, {0.5, 0.5, 0.0}, 100, 24, 24);
  const DirectLight light(s);
  RenderSettings gouraud;
  gouraud.antialias = 1;
  gouraud.progress = false;
  const Image g = render(mesh, bvh, cam, B, field, gouraud);
  const Image f = render(mesh, bvh, cam, B, field, raytraced(8, 256), nullptr, &light);
  double diff = 0.0;
  for (size_t k = 0; k < g.rgb.size(); ++k) diff += std::abs(f.rgb[k] - g.rgb[k]) * M_PI;
  diff /= static_cast<double>(g.rgb.size());
  EXPECT_LT(diff, estimate) << "estimate " << estimate;
  EXPECT_GT(diff, 0.0);  // the two shadings are different computations
}

TEST(ViewPass, IdenticalImagesForOneAndTwoThreads) {
  // Mirror, glass and a final gather: every random number is keyed by pixel and sample.
  Scene s = cube_of();
  add_rect(s, "mirror", mirror({0.8, 0.8, 0.8}), 0.1, 0.6, 0.1, 0.6, 0.001, true);
  add_outward_box(s, "slab", glass({1, 0.9, 0.8}), {0.55, 0.5, 0.2}, {0.85, 0.8, 0.4});
  const PatchMesh mesh = mesh_scene(s, {0.25, 0});
  const Bvh bvh(mesh);
  Eigen::MatrixX3d B = emission_of(mesh);
  for (std::int32_t i = 0; i < mesh.size(); ++i) B.row(i).array() += 0.3;
  const VertexField field = interpolate_to_vertices(mesh, B);
  const DirectLight light(s);
  const Camera cam = camera({0.5, 0.05, 0.6}, {0.5, 0.9, 0.3}, 80, 24, 18);
  for (int gather : {0, 4}) {
    RenderSettings o = raytraced(8, gather);
    o.antialias = 2;
    o.threads = 1;
    RenderStats one_stats, two_stats;
    const Image one = render(mesh, bvh, cam, B, field, o, &one_stats, &light);
    o.threads = 2;
    const Image two = render(mesh, bvh, cam, B, field, o, &two_stats, &light);
    EXPECT_EQ(one.rgb, two.rgb) << gather;
    EXPECT_EQ(one.alpha, two.alpha);
    EXPECT_EQ(one_stats.rays, two_stats.rays);
    EXPECT_GT(one_stats.rays, 24 * 18 * 4);  // specular and gather rays on top of the camera's
  }
}

}  // namespace lambert
