#include "bench/scene_generator.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "bench/obj_writer.hpp"
#include "common/temp_dir.hpp"
#include "core/error.hpp"
#include "io/obj_loader.hpp"

namespace lambert {
namespace {

struct Object {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0.0;   // of the vertices about their mean
  double volume = 0.0;   // signed: positive when every face is wound outward
  int inward_faces = 0;  // faces whose normal points towards the centre
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;  // vertex bounds
};

// The generated objects, measured from their vertices and faces alone.
std::vector<Object> objects(const Scene& s) {
  std::vector<Object> out;
  for (std::size_t surf = 0; surf < s.surfaces.size(); ++surf) {
    if (s.surfaces[surf].name.rfind("object_", 0) != 0) continue;
    std::vector<const Face*> faces;
    for (const Face& f : s.faces)
      if (f.surface == static_cast<std::int32_t>(surf)) faces.push_back(&f);
    Object o;
    double n = 0;
    for (const Face* f : faces) {
      for (auto v : f->vertices) {
        o.centre += s.vertices[v], ++n;
        o.lo = o.lo.cwiseMin(s.vertices[v]), o.hi = o.hi.cwiseMax(s.vertices[v]);
      }
    }
    o.centre /= n;
    for (const Face* f : faces) {
      const Eigen::Vector3d a = s.vertices[f->vertices[0]] - o.centre;
      const Eigen::Vector3d b = s.vertices[f->vertices[1]] - o.centre;
      const Eigen::Vector3d c = s.vertices[f->vertices[2]] - o.centre;
      o.volume += a.dot(b.cross(c)) / 6.0;
      o.inward_faces += (b - a).cross(c - a).dot(a + b + c) <= 0.0;
      o.radius = std::max({o.radius, a.norm(), b.norm(), c.norm()});
    }
    out.push_back(o);
  }
  return out;
}

TEST(SceneGenerator, HitsTheTargetTriangleCount) {
  // The last object's k is rounded: at most 8 (2k + 1) triangles off (header), k ~ 3 at
  // 10^3 (16 objects of ~60 triangles): 56 / 1000 = 5.6 % at worst; the header promises 3 %
  // at 10^3 and 0.5 % from 10^4 for the default seed, which this checks.
  for (const auto& [target, rel] :
       {std::pair{1000, 0.03}, std::pair{10000, 0.005}, std::pair{30000, 0.005}}) {
    const Scene s = bench::cornell_with_objects(target, 1);
    const double n = static_cast<double>(bench::triangle_count(s));
    EXPECT_NEAR(n / target, 1.0, rel) << "target " << target << ": " << n;
  }
}

TEST(SceneGenerator, ObjectsAreClosedOutwardAndApartInsideTheRoom) {
  const Scene s = bench::cornell_with_objects(10000, 7);
  const std::vector<Object> objs = objects(s);
  ASSERT_EQ(objs.size(), 50u);  // round(sqrt(10^4) / 2)
  const Scene box = load_obj(builtin_cornell_box_path());
  const auto [lo, hi] = box.bounds();
  for (std::size_t i = 0; i < objs.size(); ++i) {
    EXPECT_EQ(objs[i].inward_faces, 0) << i;
    EXPECT_GT(objs[i].volume, 0.0) << i;
    EXPECT_TRUE((objs[i].lo.array() > lo.array()).all()) << i;
    EXPECT_TRUE((objs[i].hi.array() < hi.array()).all()) << i;
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GT((objs[i].centre - objs[j].centre).norm(), objs[i].radius + objs[j].radius)
          << i << " " << j;
  }
}

TEST(SceneGenerator, IsDeterministicPerSeed) {
  const Scene a = bench::cornell_with_objects(3000, 5), b = bench::cornell_with_objects(3000, 5);
  const Scene c = bench::cornell_with_objects(3000, 6);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (std::size_t v = 0; v < a.vertices.size(); ++v) ASSERT_EQ(a.vertices[v], b.vertices[v]);
  EXPECT_NE(a.vertices.back(), c.vertices.back());
}

TEST(SceneGenerator, RefusesTargetsBelowTheBox) {
  EXPECT_THROW(bench::cornell_with_objects(10, 1), UsageError);
}

TEST(ObjWriter, GeneratedSceneRoundTripsThroughTheLoader) {
  const testing::TempDir dir;
  const Scene s = bench::cornell_with_objects(2000, 3);
  bench::write_obj(s, dir.file("gen.obj"));
  LoadReport report;
  LoadOptions strict;
  strict.strict = true;
  const Scene r = load_obj(dir.file("gen.obj"), &report, strict);
  EXPECT_EQ(report.degenerate_faces_dropped, 0);
  EXPECT_EQ(report.skipped_statements, 0);
  ASSERT_EQ(r.faces.size(), s.faces.size());
  EXPECT_EQ(bench::triangle_count(r), bench::triangle_count(s));
  EXPECT_EQ(r.surfaces.size(), s.surfaces.size());
  EXPECT_NEAR(r.total_area(), s.total_area(), 1e-9 * s.total_area());  // 17 digits written
  int emitters = 0;
  for (std::size_t i = 0; i < r.surfaces.size(); ++i)
    if (r.material_of(static_cast<std::int32_t>(i)).emits()) {
      ++emitters;
      EXPECT_EQ(r.surfaces[i].name, "light");
    }
  EXPECT_EQ(emitters, 1);
  EXPECT_TRUE(r.camera.defined);
  EXPECT_NEAR(r.camera.vfov_degrees, s.camera.vfov_degrees, 1e-12);
}

}  // namespace
}  // namespace lambert
