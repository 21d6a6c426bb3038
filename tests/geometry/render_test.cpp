#include "geometry/render/render.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace lambert {
namespace {

const Material kWhite{"white", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};

// An open box (x, y in [0, 1], z in [0, 1]) with its opening at z = 0 and every face wound
// to point inward, seen from outside through the opening (like the Cornell box): every
// visible hit is a front face. Quads (back, floor, ceiling) and triangle pairs (side walls).
Scene open_box() {
  Scene s;
  const Eigen::Vector3d p[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  add_polygon(s, "back", kWhite, {p[4], p[7], p[6], p[5]});   // z = 1, normal -z
  add_polygon(s, "floor", kWhite, {p[0], p[4], p[5], p[1]});  // y = 0, normal +y
  add_polygon(s, "left", kWhite, {p[0], p[3], p[7]});         // x = 0, normal +x
  add_polygon(s, "left", kWhite, {p[0], p[7], p[4]});
  add_polygon(s, "right", kWhite, {p[1], p[5], p[6]});  // x = 1, normal -x
  add_polygon(s, "right", kWhite, {p[1], p[6], p[2]});
  add_polygon(s, "ceiling", kWhite, {p[3], p[2], p[6], p[7]});  // y = 1, normal -y
  return s;
}

Camera box_camera(int w, int h) {
  Camera c;
  c.eye = Eigen::Vector3d(0.5, 0.5, -1.6);
  c.look_at = Eigen::Vector3d(0.5, 0.5, 1.0);
  c.vfov_degrees = 45.0;  // wider than the opening: some pixels miss
  c.width = w;
  c.height = h;
  c.defined = true;
  return c;
}

}  // namespace

TEST(Render, OpenBoxFacesPointInward) {
  const PatchMesh mesh = mesh_scene(open_box(), {0.5, 0});
  const Eigen::Vector3d centre(0.5, 0.5, 0.5);
  for (const auto& p : mesh.patches) EXPECT_GT(p.normal.dot(centre - p.centroid), 0.0);
}

TEST(Render, UniformRadiosityGivesBOverPiInEveryPixelThatHits) {
  const PatchMesh mesh = mesh_scene(open_box(), {0.15, 0});
  const Bvh bvh(mesh);
  const Eigen::RowVector3d b(1.0, 2.0, 4.0);
  const Eigen::MatrixX3d B = b.replicate(mesh.size(), 1);
  const VertexField field = interpolate_to_vertices(mesh, B);
  for (bool flat : {false, true}) {
    RenderSettings o;
    o.shading = flat ? Shading::Flat : Shading::Gouraud;
    o.antialias = 3;
    o.progress = false;
    RenderStats stats;
    const Image img = render(mesh, bvh, box_camera(48, 40), B, field, o, &stats);
    EXPECT_EQ(stats.rays, 48 * 40 * 9);
    int full = 0, partial = 0, empty = 0;
    for (int y = 0; y < img.height; ++y) {
      for (int x = 0; x < img.width; ++x) {
        const float a = img.alpha[static_cast<size_t>(y) * img.width + x];
        const Eigen::Vector3f L = img.pixel(x, y);
        full += a == 1.0f;
        partial += a > 0.0f && a < 1.0f;
        empty += a == 0.0f;
        // A pixel is the mean over its samples of B/π (hit) or 0 (miss): alpha · B/π. The
        // Gouraud weights sum to 1 within 1e-15 and a constant field interpolates exactly;
        // the float store rounds to relative 2^-24 = 6e-8: 1e-6 relative is a safe bound.
        for (int c = 0; c < 3; ++c) {
          const double expected = a * b[c] / M_PI;
          EXPECT_NEAR(L[c], expected, 1e-6 * b[c]) << "pixel " << x << "," << y;
        }
      }
    }
    EXPECT_GT(full, 500);
    EXPECT_GT(partial, 0);
    EXPECT_GT(empty, 0);
  }
}

// The wireframe darkens only pixels near patch edges: with a uniform field, every pixel is
// either its plain value (far from edges) or darker (a sample within half a pixel of an
// edge is black), never brighter; darkened pixels exist and are a minority at 0.15 edges
// (about 18 pixels across a patch here, two or three of them on its edges).
TEST(Render, WireframeDarkensOnlyPixelsNearPatchEdges) {
  const PatchMesh mesh = mesh_scene(open_box(), {0.15, 0});
  const Bvh bvh(mesh);
  const Eigen::MatrixX3d B = Eigen::RowVector3d(1.0, 1.0, 1.0).replicate(mesh.size(), 1);
  const VertexField field = interpolate_to_vertices(mesh, B);
  RenderSettings o;
  o.antialias = 3;
  o.progress = false;
  const Image plain = render(mesh, bvh, box_camera(288, 240), B, field, o);
  o.wireframe = true;
  const Image wire = render(mesh, bvh, box_camera(288, 240), B, field, o);
  int darker = 0, hits = 0;
  for (int y = 0; y < wire.height; ++y)
    for (int x = 0; x < wire.width; ++x) {
      const float a = plain.pixel(x, y)[0], b = wire.pixel(x, y)[0];
      EXPECT_LE(b, a * (1 + 1e-6f));
      hits += a > 0;
      darker += b < a * (1 - 1e-6f);
    }
  EXPECT_GT(darker, hits / 20);
  EXPECT_LT(darker, hits * 3 / 4);
}

TEST(Render, GouraudReproducesALinearFieldAtTheHitPoint) {
  // Vertex values linear in position are reproduced exactly by barycentric/bilinear
  // interpolation on planar patches, so each centre-sampled pixel shows f(hit)/π.
  const PatchMesh mesh = mesh_scene(open_box(), {0.2, 0});
  const Bvh bvh(mesh);
  auto f = [](const Eigen::Vector3d& x) { return 1.0 + 0.5 * x.x() + 0.25 * x.y() + x.z(); };
  VertexField field = build_shading_vertices(mesh);
  for (std::int32_t k = 0; k < field.size(); ++k)
    field.values.row(k).setConstant(f(field.positions[k]));
  const Eigen::MatrixX3d B = Eigen::MatrixX3d::Ones(mesh.size(), 3);  // unused (Gouraud)
  RenderSettings o;
  o.antialias = 1;
  o.progress = false;
  const Camera cam = box_camera(32, 32);
  const Image img = render(mesh, bvh, cam, B, field, o);
  int checked = 0;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      if (img.alpha[static_cast<size_t>(y) * cam.width + x] == 0.0f) continue;
      // The exact hit: intersect the pixel-centre ray with the box planes analytically.
      const Eigen::Vector3d d = cam.ray_direction(x + 0.5, y + 0.5);
      double t_best = INFINITY;
      for (int axis = 0; axis < 3; ++axis) {
        for (double plane : {0.0, 1.0}) {
          if (axis == 2 && plane == 0.0) continue;  // the opening
          if (d[axis] == 0) continue;
          const double t = (plane - cam.eye[axis]) / d[axis];
          const Eigen::Vector3d hit = cam.eye + t * d;
          bool in = t > 0;
          for (int a = 0; a < 3; ++a) in = in && hit[a] >= -1e-12 && hit[a] <= 1 + 1e-12;
          if (in && t < t_best) t_best = t;
        }
      }
      ASSERT_TRUE(std::isfinite(t_best));
      const double expected = f(cam.eye + t_best * d) / M_PI;
      // Embree's float hit distance t ~ 2 carries relative error ~1e-7 (a few float ulps), so
      // the hit point moves by <= ~1e-6 along a ray of |d| ~ 1 and f (|∇f| ~ 1.2) by ~1e-6;
      // plus the float store (6e-8 relative): 1e-5 is a safe bound.
      EXPECT_NEAR(img.pixel(x, y)[0], expected, 1e-5) << "pixel " << x << "," << y;
      ++checked;
    }
  }
  EXPECT_GT(checked, 300);
}

TEST(Render, ImageIsIdenticalForAnyThreadCount) {
  const PatchMesh mesh = mesh_scene(open_box(), {0.2, 0});
  const Bvh bvh(mesh);
  Eigen::MatrixX3d B(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i) B.row(i) = mesh.patches[i].centroid.transpose();
  const VertexField field = interpolate_to_vertices(mesh, B);
  RenderSettings o;
  o.progress = false;
  o.antialias = 2;
  o.threads = 1;
  const Image one = render(mesh, bvh, box_camera(40, 30), B, field, o);
  o.threads = 2;
  const Image two = render(mesh, bvh, box_camera(40, 30), B, field, o);
  EXPECT_EQ(one.rgb, two.rgb);
  EXPECT_EQ(one.alpha, two.alpha);
}

}  // namespace lambert

namespace lambert {

TEST(RenderMedium, CameraRaysAreAttenuatedAndCollectTheVoxelsExactly) {
  // The open box with uniform B = b, filled (x, y, z in [0, 1]) by a medium of sigma_t 2 in
  // 4^3 voxels whose radiosity is s (source radiance s / pi).
  const PatchMesh mesh = mesh_scene(open_box(), {0.25, 0});
  const Bvh bvh(mesh);
  const Eigen::RowVector3d b(1.0, 2.0, 4.0), s(3.0, 1.0, 0.5);
  const Eigen::MatrixX3d B = b.replicate(mesh.size(), 1);
  const Medium medium =
      homogeneous_medium({0, 0, 0}, {1, 1, 1}, {4, 4, 4}, Eigen::Vector3d::Constant(0.5),
                         Eigen::Vector3d::Constant(1.5), Eigen::Vector3d::Zero());
  MediumView view;
  view.medium = &medium;
  view.voxel_B = s.replicate(medium.voxels(), 1);
  RenderSettings o;
  o.shading = Shading::Flat;
  o.antialias = 1;
  o.progress = false;
  o.medium = &view;
  const Camera cam = box_camera(33, 33);
  const Image img = render(mesh, bvh, cam, B, VertexField{}, o);
  // The centre pixel's ray enters the medium at z = 0 and hits the back wall at z = 1: the
  // length inside is l = |d| / d_z; L = (exp(-2 l) b + (1 - exp(-2 l)) s) / pi. The DDA sums
  // 4 voxel segments exactly; the float BVH hit (relative ~1e-7 of t) moves l by ~3e-7, so
  // L by ~1e-6 relative: 1e-5 is the bound with a margin.
  const Eigen::Vector3d d = cam.ray_direction(16.5, 16.5);
  const double l = d.norm() / d.z();
  const double T = std::exp(-2.0 * l);
  const Eigen::Vector3f px = img.pixel(16, 16);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(px[c], (T * b[c] + (1 - T) * s[c]) / M_PI, 1e-5 * b.maxCoeff()) << c;
  // A medium in equilibrium with the walls (s = b) is invisible: every hit pixel is b / pi.
  view.voxel_B = b.replicate(medium.voxels(), 1);
  const Image same = render(mesh, bvh, cam, B, VertexField{}, o);
  for (int y = 0; y < same.height; ++y)
    for (int x = 0; x < same.width; ++x)
      if (same.alpha[y * same.width + x] == 1.0f) {
        for (int c = 0; c < 3; ++c)  // float pixels: 1e-6 relative
          ASSERT_NEAR(same.pixel(x, y)[c], b[c] / M_PI, 1e-6 * b[c]) << x << "," << y;
      }
}

}  // namespace lambert

namespace lambert {

// Each corner of the box [lo, hi], seen from the eye in the camera's frame, lies within the
// field of view (the frame's half-height tan(vfov/2) at unit depth; the image is square).
void expect_box_in_frame(const Camera& c, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                         const std::string& view) {
  const Eigen::Vector3d forward = (c.look_at - c.eye).normalized();
  const Eigen::Vector3d right = forward.cross(c.up).normalized(), top = right.cross(forward);
  const double half = std::tan(0.5 * c.vfov_degrees * M_PI / 180.0);
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(),
                            k & 4 ? hi.z() : lo.z());
    const Eigen::Vector3d d = p - c.eye;
    const double depth = d.dot(forward);
    ASSERT_GT(depth, 0.0) << view << k;
    EXPECT_LT(std::abs(d.dot(right)) / depth, half) << view << k;
    EXPECT_LT(std::abs(d.dot(top)) / depth, half) << view << k;
  }
}

TEST(Camera, TheDefaultViewIsAThreeQuarterViewThatFramesTheWholeBox) {
  // Issue 35: a flat part framed head-on was seen edge-on. The default view looks down at 30°
  // from 35° round the front, along the scene's up axis, and every corner of the box lies
  // inside the image.
  const Eigen::Vector3d lo(-5, 0, -5), hi(5, 0.2, 5);  // a thin y-up plate
  for (int up : {1, 2}) {
    const Camera c = three_quarter_camera(lo, hi, up);
    EXPECT_EQ(camera_problem(c), "");
    const Eigen::Vector3d u = up == 2 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d forward = (c.look_at - c.eye).normalized();
    EXPECT_NEAR(-forward.dot(u), 0.5, 1e-12);  // sin 30°
    EXPECT_EQ(c.up, u);
    expect_box_in_frame(c, lo, hi, "three-quarter");
  }
}

TEST(Camera, TheNamedViewsFrameTheWholeBoxFromTheirSides) {
  // --view: front (level, from the front: -z for y up, -y for z up), top (straight down, the
  // front at the picture's bottom) and three-quarter (sin 30° down); each a valid camera with
  // every corner of the box inside the frame.
  const Eigen::Vector3d lo(-5, -1, -3), hi(5, 2, 4);
  for (int up : {1, 2}) {
    const Eigen::Vector3d u = up == 2 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d front = up == 2 ? -Eigen::Vector3d::UnitY() : -Eigen::Vector3d::UnitZ();
    for (const std::string view : {"front", "top", "three-quarter"}) {
      const Camera c = view_camera(lo, hi, up, view);
      EXPECT_EQ(camera_problem(c), "") << view;
      const Eigen::Vector3d forward = (c.look_at - c.eye).normalized();
      if (view == "front") {
        EXPECT_NEAR(forward.dot(-front), 1.0, 1e-12);
        EXPECT_EQ(c.up, u);
      } else if (view == "top") {
        EXPECT_NEAR(forward.dot(-u), 1.0, 1e-12);
        EXPECT_EQ(c.up, -front);  // the front at the bottom of the picture
      } else {
        EXPECT_NEAR(-forward.dot(u), 0.5, 1e-12);
      }
      expect_box_in_frame(c, lo, hi, view);
    }
  }
}

}  // namespace lambert
