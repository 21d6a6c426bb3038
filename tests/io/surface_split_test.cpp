// --split-angle (io/surface_split.hpp): a box into its six faces, a tessellated cylinder into
// its caps and side, the angle boundary (exactly DEG keeps faces together), non-manifold
// edges, names in first-facet order, and today's surfaces when the option is off.
#include "io/surface_split.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "common/stl_text.hpp"
#include "core/error.hpp"
#include "geometry/polygon.hpp"
#include "io/obj_loader.hpp"
#include "io/stl_loader.hpp"

namespace lambert {
namespace {

using V = Eigen::Vector3d;
using Triangle = testing::StlTriangle;

// Binary STL of `tris` (float32 corners; the tests use coordinates floats hold exactly).
std::string binary_stl(const std::vector<Triangle>& tris) {
  std::string s(80, ' ');
  const auto n = static_cast<std::uint32_t>(tris.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  const auto put = [&s](double x) {
    const auto f = static_cast<float>(x);
    char b[4];
    std::memcpy(b, &f, 4);  // little-endian hosts, as STL is
    s.append(b, 4);
  };
  for (const auto& t : tris) {
    for (int k = 0; k < 3; ++k) put(0.0);  // no stored normal
    for (const auto& p : t)
      for (int k = 0; k < 3; ++k) put(p[k]);
    s.append(2, '\0');
  }
  return s;
}

// ASCII STL of one solid (tests/common/stl_text.hpp).
std::string ascii_stl(const std::string& solid, const std::vector<Triangle>& tris) {
  return testing::ascii_stl({{solid, tris}});
}

// A quad (counter-clockwise about its front) as two triangles, appended to `out`.
void add_quad(std::vector<Triangle>& out, V a, V b, V c, V d) {
  out.push_back({a, b, c});
  out.push_back({a, c, d});
}

// An axis-aligned box [lo, hi], outward fronts: 12 triangles, two per face.
std::vector<Triangle> box(V lo, V hi) {
  std::vector<Triangle> t;
  const auto p = [&](int x, int y, int z) {
    return V(x ? hi.x() : lo.x(), y ? hi.y() : lo.y(), z ? hi.z() : lo.z());
  };
  add_quad(t, p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0));  // z = lo
  add_quad(t, p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1));  // z = hi
  add_quad(t, p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1));  // y = lo
  add_quad(t, p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0));  // y = hi
  add_quad(t, p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0));  // x = lo
  add_quad(t, p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1));  // x = hi
  return t;
}

// A closed cylinder of radius r and height h on z = 0 with `sides` facets around: two cap
// fans and the side (two triangles per facet), outward fronts.
std::vector<Triangle> cylinder(double r, double h, int sides) {
  std::vector<Triangle> t;
  const auto at = [&](int k, double z) {
    const double a = 2.0 * M_PI * k / sides;
    return V(r * std::cos(a), r * std::sin(a), z);
  };
  for (int k = 0; k < sides; ++k) {
    t.push_back({V(0, 0, 0), at(k + 1, 0), at(k, 0)});  // bottom, facing -z
    t.push_back({V(0, 0, h), at(k, h), at(k + 1, h)});  // top, facing +z
    add_quad(t, at(k, 0), at(k + 1, 0), at(k + 1, h), at(k, h));
  }
  return t;
}

// Area of every surface, by name.
std::map<std::string, double> areas(const Scene& s) {
  std::map<std::string, double> a;
  for (const auto& sf : s.surfaces) a[sf.name] = 0.0;
  for (const Face& f : s.faces) {
    std::vector<V> poly;
    for (auto v : f.vertices) poly.push_back(s.vertices[v]);
    a[s.surfaces[f.surface].name] += polygon_area(poly);
  }
  return a;
}

LoadOptions split_at(double deg) {
  LoadOptions o;
  o.split_angle = deg;
  return o;
}

TEST(SurfaceSplit, BoxSplitsIntoItsSixFacesNamedInFacetOrder) {
  const std::string stl = binary_stl(box(V(0, 0, 0), V(2, 2, 2)));
  const Scene whole = load_stl_bytes(stl, "box.stl");
  ASSERT_EQ(whole.surfaces.size(), 1u);
  EXPECT_EQ(whole.surfaces[0].name, "box");
  const Scene split = load_stl_bytes(stl, "box.stl", nullptr, split_at(30));
  ASSERT_EQ(split.surfaces.size(), 6u);
  const auto a = areas(split);
  for (int k = 1; k <= 6; ++k) {
    const std::string name = "box/face_" + std::to_string(k);
    ASSERT_TRUE(a.count(name)) << name;
    EXPECT_DOUBLE_EQ(a.at(name), 4.0) << name;  // side^2, exact in binary
    // Numbered by first facet: facets 2k-2 and 2k-1 (the order box() writes) are face_k.
    EXPECT_EQ(split.surfaces[split.faces[2 * k - 2].surface].name, name);
    EXPECT_EQ(split.faces[2 * k - 1].surface, split.faces[2 * k - 2].surface);
  }
}

TEST(SurfaceSplit, ExactlyTheAngleKeepsFacesTogether) {
  // The box's edges turn by exactly 90 degrees: <= keeps them, just below splits them.
  const std::string stl = binary_stl(box(V(0, 0, 0), V(1, 1, 1)));
  EXPECT_EQ(load_stl_bytes(stl, "b.stl", nullptr, split_at(90)).surfaces.size(), 1u);
  EXPECT_EQ(load_stl_bytes(stl, "b.stl", nullptr, split_at(89.999)).surfaces.size(), 6u);
  // Angle 0: only coplanar neighbours stay together (each face's two triangles).
  EXPECT_EQ(load_stl_bytes(stl, "b.stl", nullptr, split_at(0)).surfaces.size(), 6u);
  EXPECT_EQ(load_stl_bytes(stl, "b.stl", nullptr, split_at(180)).surfaces.size(), 1u);
}

TEST(SurfaceSplit, CylinderGivesTwoCapsAndOneSideWithExactAreas) {
  const int n = 64;
  const double r = 0.5, h = 2.0;
  const std::string stl = ascii_stl("can", cylinder(r, h, n));
  EXPECT_EQ(load_stl_bytes(stl, "can.stl").surfaces.size(), 1u);
  const Scene s = load_stl_bytes(stl, "can.stl", nullptr, split_at(30));
  ASSERT_EQ(s.surfaces.size(), 3u);
  const auto a = areas(s);
  // First facets: bottom fan (facet 0), top fan (facet 1), side (facet 2).
  const double cap = 0.5 * n * r * r * std::sin(2.0 * M_PI / n);  // the regular n-gon
  const double side = n * 2.0 * r * std::sin(M_PI / n) * h;       // n rectangles
  // The corners are the doubles written with 17 digits (read back exactly): the areas differ
  // from the closed forms by summation rounding only, ~n ulps.
  EXPECT_NEAR(a.at("can/face_1"), cap, 1e-13);
  EXPECT_NEAR(a.at("can/face_2"), cap, 1e-13);
  EXPECT_NEAR(a.at("can/face_3"), side, 1e-13);
  // The side's facets turn by 360/64 = 5.625 degrees: split below that, one piece above.
  EXPECT_EQ(load_stl_bytes(stl, "can.stl", nullptr, split_at(5.6)).surfaces.size(), 2u + n);
  EXPECT_EQ(load_stl_bytes(stl, "can.stl", nullptr, split_at(5.7)).surfaces.size(), 3u);
}

TEST(SurfaceSplit, NonManifoldEdgeSeparatesItsFaces) {
  // Three triangles on the edge (0,0,0)-(1,0,0): a flat pair and a fin up. Even at 180
  // degrees, which keeps every manifold edge, the three separate.
  const std::vector<Triangle> t = {{V(0, 0, 0), V(1, 0, 0), V(0.5, 1, 0)},
                                   {V(1, 0, 0), V(0, 0, 0), V(0.5, -1, 0)},
                                   {V(0, 0, 0), V(1, 0, 0), V(0.5, 0, 1)}};
  const Scene s = load_stl_bytes(ascii_stl("fin", t), "x.stl", nullptr, split_at(180));
  EXPECT_EQ(s.surfaces.size(), 3u);
}

TEST(SurfaceSplit, SolidsAndComponentsSplitEachOnItsOwn) {
  // Two ASCII solids: a box splits into six, a flat square (two coplanar triangles) keeps its
  // name. Binary: two boxes apart are box_1 and box_2, then each splits.
  std::vector<Triangle> sq;
  add_quad(sq, V(5, 0, 0), V(6, 0, 0), V(6, 1, 0), V(5, 1, 0));
  const std::string two = ascii_stl("cube", box(V(0, 0, 0), V(1, 1, 1))) + ascii_stl("tile", sq);
  const Scene a = load_stl_bytes(two, "t.stl", nullptr, split_at(30));
  ASSERT_EQ(a.surfaces.size(), 7u);
  EXPECT_EQ(a.surfaces.front().name, "cube/face_1");
  EXPECT_EQ(a.surfaces.back().name, "tile");
  auto boxes = box(V(0, 0, 0), V(1, 1, 1));
  const auto far = box(V(3, 0, 0), V(4, 1, 1));
  boxes.insert(boxes.end(), far.begin(), far.end());
  const Scene b = load_stl_bytes(binary_stl(boxes), "pair.stl", nullptr, split_at(30));
  ASSERT_EQ(b.surfaces.size(), 12u);
  EXPECT_EQ(b.surfaces[0].name, "pair_1/face_1");
  EXPECT_EQ(b.surfaces[11].name, "pair_2/face_6");
}

TEST(SurfaceSplit, APieceNameThatIsAlreadyASurfaceIsRefused) {
  const std::string two = ascii_stl("cube", box(V(0, 0, 0), V(1, 1, 1))) +
                          ascii_stl("cube/face_2", {{V(5, 0, 0), V(6, 0, 0), V(5, 1, 0)}});
  try {
    load_stl_bytes(two, "t.stl", nullptr, split_at(30));
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("'cube/face_2'"), std::string::npos) << e.what();
  }
}

TEST(SurfaceSplit, FortyThousandFacetsSplitIntoTheirFoldedHalves) {
  // Two 100 x 100 x 2-triangle sheets, each folded into a roof (two pieces): 40,000 facets.
  // The split is O(E log E) (prints its time beside the load's; 10^5 facets: ~0.1 s).
  const int m = 100;
  std::vector<Triangle> t;
  const auto p = [&](int i, int j) { return V(i, j, i <= m / 2 ? i : m - i); };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) add_quad(t, p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
  std::vector<Triangle> more = t;
  for (auto& tri : more)
    for (auto& c : tri) c.y() += m + 1;  // a second roof beside it
  t.insert(t.end(), more.begin(), more.end());
  const std::string stl = binary_stl(t);
  const auto t0 = std::chrono::steady_clock::now();
  const Scene whole = load_stl_bytes(stl, "roof.stl");
  const auto t1 = std::chrono::steady_clock::now();
  const Scene split = load_stl_bytes(stl, "roof.stl", nullptr, split_at(30));
  const auto t2 = std::chrono::steady_clock::now();
  EXPECT_EQ(whole.surfaces.size(), 2u);
  ASSERT_EQ(split.surfaces.size(), 4u);
  EXPECT_EQ(split.surfaces[0].name, "roof_1/face_1");
  const double load_s = std::chrono::duration<double>(t1 - t0).count();
  const double split_s = std::chrono::duration<double>(t2 - t1).count() - load_s;
  std::printf("%zu facets: load %.3f s, split adds %.3f s\n", t.size(), load_s, split_s);
}

}  // namespace
}  // namespace lambert

namespace lambert {
namespace {

TEST(SurfaceSplit, ObjCornersRepeatedUnderOtherIndicesStillJoin) {
  // Two coplanar quads and a third bent up by 90 degrees, each with its own four vertex
  // indices: edges are matched by corner position, so at 30 degrees the flat pair is one piece.
  std::istringstream obj(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "v 1 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\n"
      "v 2 0 0\nv 2 0 1\nv 2 1 1\nv 2 1 0\n"
      "g plate\nf 1 2 3 4\nf 5 6 7 8\nf 9 12 11 10\n");
  LoadOptions o;
  o.split_angle = 30;
  o.warn_without_emitter = false;
  const Scene s = load_obj_stream(obj, "p.obj", {}, nullptr, o);
  ASSERT_EQ(s.surfaces.size(), 2u);
  EXPECT_EQ(s.surfaces[0].name, "plate/face_1");
  EXPECT_EQ(s.faces[0].surface, s.faces[1].surface);
  EXPECT_NE(s.faces[2].surface, s.faces[0].surface);
}

}  // namespace
}  // namespace lambert
