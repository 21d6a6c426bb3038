// Specular MTL materials: mirrors (illum 3, 5, 8: Ks), dielectrics (illum 4, 6, 7, 9: Ni, Tf,
// Kd 0), the diffuse illum models whose Ks is a highlight, d/Tr, Ns, the refusals with their
// file:line, and the refusal of specular scenes that absorb nothing in some channel.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <memory>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "geometry/mesh/mesh.hpp"
#include "io/mtl_parser.hpp"
#include "io/obj_loader.hpp"

namespace lambert {
namespace {

// A unit floor (white), a lamp triangle facing down (lamp) and a wall (material `m`, the one
// under test) facing +x.
const char* kObj =
    "mtllib s.mtl\n"
    "g floor\nusemtl white\nv 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nf 1 2 3 4\n"
    "g lamp\nusemtl lamp\nv 0 1 0\nv 1 1 0\nv 0 1 1\nf 5 6 7\n"
    "g wall\nusemtl m\nv 0 0 0\nv 0 1 0\nv 0 1 1\nv 0 0 1\nf 8 9 10 11\n";
constexpr std::int32_t kWall = 2;  // surface index of `wall`

// The MTL's fixed head (lines 1-6, ending with `newmtl m`); `body` follows from line 7.
const char* kMtlHead = "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\nnewmtl m\n";
constexpr int kBodyLine = 7;

// "s.mtl:L: material 'm': " for the body's line `k` (1-based).
std::string at_body(int k, const std::string& material = "m") {
  return "s.mtl:" + std::to_string(kBodyLine + k - 1) + ": material '" + material + "': ";
}

// Loads OBJ and MTL text from memory (the MTL named s.mtl, the OBJ s.obj).
Scene load_text(const std::string& obj, const std::string& mtl, LoadReport* report = nullptr) {
  std::istringstream in(obj);
  const MtlOpener open = [&](const std::string&) {
    return MtlFile{std::make_unique<std::istringstream>(mtl), "s.mtl"};
  };
  return load_obj_stream(in, "s.obj", open, report);
}

// load_text of kObj with material `m` given by `body`.
Scene load_wall(const std::string& body, LoadReport* report = nullptr) {
  return load_text(kObj, std::string(kMtlHead) + body, report);
}

// The load error of kObj with `m` given by `body` ("" when it loads).
std::string wall_error(const std::string& body) {
  try {
    load_wall(body);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

// Every warning, one per line, for failure messages.
std::string all_warnings(const LoadReport& r) {
  std::string out;
  for (const auto& w : r.warnings) out += "  " + w + "\n";
  return out;
}

// A closed unit cube, fronts inward: faces 1-5 use `walls`, the top (y = 1) uses `top`.
std::string closed_box(const std::string& walls, const std::string& top) {
  const std::string corners =
      "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\n";
  const std::string sides = "f 1 4 3 2\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
  return "mtllib s.mtl\n" + corners + "g walls\nusemtl " + walls + "\n" + sides + "g top\nusemtl " +
         top + "\nf 5 6 7 8\n";
}

}  // namespace

TEST(MtlSpecular, PlainSceneLoadsWithoutWarnings) {
  // The baseline of the "no warning" checks below.
  LoadReport report;
  const Scene s = load_wall("Kd 0.3 0.3 0.3\n", &report);
  EXPECT_TRUE(report.warnings.empty()) << all_warnings(report);
  EXPECT_FALSE(s.material_of(kWall).specular.any());
}

TEST(MtlSpecular, MirrorIllumModelsTakeKsAsReflectance) {
  for (int illum : {3, 5, 8}) {
    const Scene s =
        load_wall("Kd 0 0 0\nKs 0.9 0.8 0.7\nNs 250\nillum " + std::to_string(illum) + "\n");
    const Specular& sp = s.material_of(kWall).specular;
    EXPECT_TRUE(sp.any()) << "illum " << illum;
    EXPECT_FALSE(sp.dielectric) << "illum " << illum;
    EXPECT_EQ(sp.reflectance, Eigen::Vector3d(0.9, 0.8, 0.7)) << "illum " << illum;
    EXPECT_EQ(sp.shininess, 250.0) << "illum " << illum;  // stored; treated as perfect specular
  }
}

TEST(MtlSpecular, DielectricIllumModelsTakeNiAndTf) {
  for (int illum : {4, 6, 7, 9}) {
    // Ks is unused by a dielectric (its reflection is Fresnel's).
    const Scene s = load_wall("Kd 0 0 0\nKs 0.5 0.5 0.5\nNi 1.5\nTf 0.9 0.8 0.7\nillum " +
                              std::to_string(illum) + "\n");
    const Specular& sp = s.material_of(kWall).specular;
    EXPECT_TRUE(sp.any()) << "illum " << illum;
    EXPECT_TRUE(sp.dielectric) << "illum " << illum;
    EXPECT_EQ(sp.ior, 1.5) << "illum " << illum;
    EXPECT_EQ(sp.transmission, Eigen::Vector3d(0.9, 0.8, 0.7)) << "illum " << illum;
    EXPECT_EQ(sp.reflectance, Eigen::Vector3d(0, 0, 0)) << "illum " << illum;
  }
  // MTL's defaults: Ni 1, Tf 1 1 1; a grey Tf is one number.
  const Specular d = load_wall("Kd 0\nillum 7\n").material_of(kWall).specular;
  EXPECT_TRUE(d.dielectric);
  EXPECT_EQ(d.ior, 1.0);
  EXPECT_EQ(d.transmission, Eigen::Vector3d(1, 1, 1));
  EXPECT_EQ(load_wall("Kd 0\nTf 0.25\nillum 4\n").material_of(kWall).specular.transmission,
            Eigen::Vector3d(0.25, 0.25, 0.25));
}

TEST(MtlSpecular, MirrorWithDiffusePartUpToOneIsAccepted) {
  // 0.25 + 0.75 is exactly 1 in binary: the bound itself is accepted.
  const Scene s = load_wall("Kd 0.25 0.3 0\nKs 0.75 0.5 1\nillum 3\n");
  EXPECT_EQ(s.material_of(kWall).rho, Eigen::Vector3d(0.25, 0.3, 0));
  EXPECT_EQ(s.material_of(kWall).specular.reflectance, Eigen::Vector3d(0.75, 0.5, 1));
}

TEST(MtlSpecular, MirrorReflectingMoreThanItReceivesNamesTheKsLine) {
  const std::string err = wall_error("Kd 0.5 0.5 0.5\nKs 0.6 0.4 0.4\nillum 3\n");
  EXPECT_NE(err.find(at_body(2) + "Kd 0.5 0.5 0.5 + Ks 0.6 0.4 0.4 exceeds 1"), std::string::npos)
      << err;
  // The Ks line, also when Ks comes first.
  const std::string first = wall_error("illum 5\nKs 0.6 0.6 0.6\nKd 0.5 0.5 0.5\n");
  EXPECT_NE(first.find(at_body(2) + "Kd 0.5 0.5 0.5 + Ks 0.6 0.6 0.6 exceeds 1"), std::string::npos)
      << first;
  const std::string above = wall_error("Kd 0\nKs 1.2 1 1\nillum 3\n");
  EXPECT_NE(above.find(at_body(2) + "specular reflectance Ks 1.2 1 1 must lie in [0, 1]"),
            std::string::npos)
      << above;
}

TEST(MtlSpecular, DielectricWithDiffuseReflectanceNamesTheKdLine) {
  const std::string err = wall_error("Ni 1.5\nKd 0.1 0 0\nillum 7\n");
  EXPECT_NE(err.find(at_body(2) + "a dielectric (illum 7) needs Kd 0"), std::string::npos) << err;
}

TEST(MtlSpecular, DiffuseIllumModelsIgnoreKsSilently) {
  // illum 0-2, 10 and no illum: Ks is a Phong highlight, not a mirror; Kd + Ks > 1 is no
  // error there.
  for (const char* illum : {"", "illum 0\n", "illum 1\n", "illum 2\n", "illum 10\n"}) {
    LoadReport report;
    const Scene s =
        load_wall(std::string("Kd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nNs 96\n") + illum, &report);
    EXPECT_FALSE(s.material_of(kWall).specular.any()) << illum;
    EXPECT_TRUE(report.warnings.empty()) << illum << all_warnings(report);
    EXPECT_TRUE(mesh_scene(s, {}).surface_specular.empty()) << illum;
  }
}

TEST(MtlSpecular, OutOfRangeOrMalformedValuesNameFileAndLine) {
  struct Case {
    const char* body;  // the bad statement is the body's line 2
    const char* what;
  };
  const Case cases[] = {
      {"Kd 0\nNi 0\nillum 7\n", "index of refraction Ni 0 of a dielectric (illum 7) must be > 0"},
      {"Kd 0\nNi -1.5\nillum 7\n", "index of refraction Ni -1.5 of a dielectric (illum 7) must be > 0"},
      {"Kd 0\nTf 1.5 1 1\nillum 7\n", "transmission filter Tf must lie in [0, 1]"},
      {"Kd 0\nTf -0.1\nillum 7\n", "transmission filter Tf must lie in [0, 1]"},
      {"Kd 0\nillum 11\n", "illum must be an integer from 0 to 10"},
      {"Kd 0\nillum 2.5\n", "illum must be an integer from 0 to 10"},
      {"Kd 0\nillum -1\n", "illum must be an integer from 0 to 10"},
      {"Kd 0\nd 2\n", "d must lie in [0, 1]"},
      {"Kd 0\nTr -0.5\n", "Tr must lie in [0, 1]"},
      {"Kd 0\nd -halo 1.5\n", "d must lie in [0, 1]"},
      {"Kd 0\nNs -1\n", "specular exponent Ns must be >= 0"},
      {"Kd 0\nKs spectral file.spd\nillum 3\n", "Ks spectral is not supported"},
      {"Kd 0\nKs xyz 1 1 1\nillum 3\n", "Ks xyz is not supported"},
      {"Kd 0\nTf spectral file.spd 1\nillum 7\n", "Tf spectral is not supported"},
      {"Kd 0\nNi inf\nillum 7\n", "Ni value 'inf' must be finite"},
      {"Kd 0\nKs 0.5 nan 0.5\nillum 3\n", "Ks value 'nan' must be finite"},
  };
  for (const auto& c : cases) {
    const std::string err = wall_error(c.body);
    EXPECT_NE(err.find(at_body(2) + c.what), std::string::npos) << c.body << "-> " << err;
  }
  // Malformed counts and numbers (not tied to the material: "s.mtl:L: malformed KEY").
  const Case malformed[] = {
      {"Kd 0\nKs 1 1\nillum 3\n", "malformed Ks: expected 3 numbers (r g b) or 1 (grey)"},
      {"Kd 0\nTf 1 1 1 1\nillum 7\n", "malformed Tf: expected 3 numbers (r g b) or 1 (grey)"},
      {"Kd 0\nNi 1.5 1.3\nillum 7\n", "malformed Ni: expected 1 number"},
      {"Kd 0\nNs\n", "malformed Ns: expected 1 number"},
      {"Kd 0\nillum\n", "malformed illum: expected 1 number"},
      {"Kd 0\nd 0.5 0.5\n", "malformed d: expected 1 number"},
      {"Kd 0\nNi 1,5\nillum 7\n", "malformed Ni: '1,5' is not a number"},
      {"Kd 0\nillum three\n", "malformed illum: 'three' is not a number"},
  };
  for (const auto& c : malformed) {
    const std::string err = wall_error(c.body);
    EXPECT_NE(err.find("s.mtl:" + std::to_string(kBodyLine + 1) + ": " + c.what), std::string::npos)
        << c.body << "-> " << err;
  }
  // A specular statement before any newmtl is ignored, as before specular materials (Kd and
  // Ke there stay refused); `Ni 0` on a diffuse material (exporters write it) is accepted.
  EXPECT_NO_THROW(load_text(kObj, "Ks 1 1 1\nillum 3\n" + std::string(kMtlHead) + "Kd 0\n"));
  EXPECT_NO_THROW(load_text(kObj, std::string(kMtlHead) + "Kd 0.5\nNi 0\nillum 2\n"));
}

TEST(MtlSpecular, TrIsOneMinusDissolve) {
  auto dissolve = [](const std::string& body) {
    std::istringstream in("newmtl m\n" + body);
    const auto mats = parse_mtl(in, "s.mtl");
    EXPECT_EQ(mats.size(), 1u);
    return mats.empty() ? -1.0 : mats[0].dissolve;
  };
  EXPECT_EQ(dissolve(""), 1.0);  // opaque by default
  EXPECT_EQ(dissolve("d 0.75\n"), 0.75);
  EXPECT_EQ(dissolve("Tr 0.25\n"), 0.75);  // 1 - 0.25 is exact in binary
  EXPECT_EQ(dissolve("Tr 0\n"), 1.0);
  EXPECT_EQ(dissolve("d -halo 0.5\n"), 0.5);
  EXPECT_EQ(dissolve("d 0.5\nTr 0.125\n"), 0.875);  // the later statement wins
}

TEST(MtlSpecular, TransparencyWithoutRefractionIsOneWarning) {
  // d < 1 (or Tr > 0) on a non-dielectric: one warning naming the material.
  for (const char* body :
       {"Kd 0.3\nd 0.5\n", "Kd 0.3\nTr 0.5\n", "Kd 0\nKs 0.5\nd 0.5\nillum 3\n"}) {
    LoadReport report;
    load_wall(body, &report);
    ASSERT_EQ(report.warnings.size(), 1u) << body << all_warnings(report);
    EXPECT_NE(report.warnings[0].find("d/Tr < 1 of material(s) 'm' ignored"), std::string::npos)
        << report.warnings[0];
  }
  // Opaque (d 1, Tr 0) and dielectrics (whose d is their refraction) are not warned about.
  for (const char* body : {"Kd 0.3\nd 1\n", "Kd 0.3\nTr 0\n", "Kd 0\nd 0.5\nillum 7\n"}) {
    LoadReport report;
    load_wall(body, &report);
    EXPECT_TRUE(report.warnings.empty()) << body << all_warnings(report);
  }
}

TEST(MtlSpecular, ClosedSceneThatAbsorbsNothingIsRefused) {
  const std::string mirror = "newmtl mirror\nKd 0 0 0\nKs 1 1 1\nillum 3\nKe 1 1 1\n";
  std::string err;
  try {
    load_text(closed_box("mirror", "mirror"), mirror);
  } catch (const SceneError& e) {
    err = e.what();
  }
  EXPECT_NE(err.find("s.obj: no surface absorbs red light"), std::string::npos) << err;
  // Kd + Ks = 1 counts as lossless too, and the check is per channel.
  const std::string mixed =
      "newmtl a\nKd 0.5 0.5 0.25\nKs 0.5 0.25 0.75\nillum 3\n"
      "newmtl b\nKd 0 0 0\nKs 0.5 0.5 1\nillum 8\n";
  err.clear();
  try {
    load_text(closed_box("a", "b"), mixed);
  } catch (const SceneError& e) {
    err = e.what();
  }
  EXPECT_NE(err.find("s.obj: no surface absorbs blue light"), std::string::npos) << err;
  // Dielectrics with Tf = 1 everywhere.
  err.clear();
  try {
    load_text(closed_box("glass", "glass"), "newmtl glass\nKd 0\nNi 1.5\nillum 7\n");
  } catch (const SceneError& e) {
    err = e.what();
  }
  EXPECT_NE(err.find("s.obj: no surface absorbs red light"), std::string::npos) << err;
}

TEST(MtlSpecular, PerfectMirrorIsAcceptedWhenSomeSurfaceAbsorbs) {
  const std::string mtl =
      "newmtl mirror\nKd 0 0 0\nKs 1 1 1\nillum 3\n"
      "newmtl grey\nKd 0.5 0.5 0.5\nKe 1 1 1\n";
  const Scene s = load_text(closed_box("mirror", "grey"), mtl);
  ASSERT_EQ(s.surfaces.size(), 2u);
  EXPECT_EQ(s.material_of(0).specular.reflectance, Eigen::Vector3d(1, 1, 1));
  EXPECT_FALSE(s.material_of(1).specular.any());
  const PatchMesh m = mesh_scene(s, {});
  ASSERT_EQ(m.surface_specular.size(), 2u);
  EXPECT_TRUE(m.has_specular());
  for (std::int32_t i = 0; i < m.size(); ++i)
    EXPECT_EQ(m.specular_of(i) != nullptr, m.patches[i].surface == 0) << "patch " << i;
}

TEST(MtlSpecular, BuiltinCornellBoxHasNoSpecularSurface) {
  // Its MTL has `Ks 0 0 0` and `illum 1` (diffuse) on every material.
  LoadReport report;
  const Scene s = load_obj(builtin_cornell_box_path(), &report);
  for (const auto& mat : s.materials) EXPECT_FALSE(mat.specular.any()) << mat.name;
  const PatchMesh m = mesh_scene(s, {});
  EXPECT_TRUE(m.surface_specular.empty());
  EXPECT_FALSE(m.has_specular());
  EXPECT_EQ(m.specular_of(0), nullptr);
}

TEST(MtlSpecular, SpecularCornellBoxHasAMirrorBlockAndAGlassSphere) {
  const Scene s = load_obj(std::string(LAMBERT_TEST_DATA_DIR) +
                           "/cornell_box_specular/cornell_box_specular.obj");
  ASSERT_EQ(s.surfaces.size(), 8u);
  std::int32_t block = -1, sphere = -1;
  for (std::int32_t k = 0; k < static_cast<std::int32_t>(s.surfaces.size()); ++k) {
    if (s.surfaces[k].name == "tall_block") block = k;
    if (s.surfaces[k].name == "glass_sphere") sphere = k;
  }
  ASSERT_GE(block, 0);
  ASSERT_GE(sphere, 0);
  const Specular& mirror = s.material_of(block).specular;
  EXPECT_FALSE(mirror.dielectric);
  EXPECT_EQ(mirror.reflectance, Eigen::Vector3d(0.95, 0.95, 0.95));
  EXPECT_EQ(s.material_of(block).rho, Eigen::Vector3d(0, 0, 0));
  const Specular& glass = s.material_of(sphere).specular;
  EXPECT_TRUE(glass.dielectric);
  EXPECT_EQ(glass.ior, 1.5);
  EXPECT_EQ(glass.transmission, Eigen::Vector3d(1, 1, 1));
  // The sphere: closed and wound outward (every face's right-hand normal points away from
  // the mean of its vertices), resting 0.5 mm above the floor.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int corners = 0;
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& f : s.faces) {
    if (f.surface != sphere) continue;
    for (auto v : f.vertices) {
      centre += s.vertices[v];
      ++corners;
      lowest = std::min(lowest, s.vertices[v].y());
    }
  }
  centre /= corners;
  int faces = 0;
  for (const auto& f : s.faces) {
    if (f.surface != sphere) continue;
    ASSERT_EQ(f.vertices.size(), 3u);
    const Eigen::Vector3d a = s.vertices[f.vertices[0]], b = s.vertices[f.vertices[1]],
                          c = s.vertices[f.vertices[2]];
    EXPECT_GT((b - a).cross(c - a).dot(a - centre), 0.0) << "face at line " << f.line;
    ++faces;
  }
  EXPECT_EQ(faces, 1280);
  // The lowest vertex is the sphere's pole, written as "0.5" and read correctly rounded.
  EXPECT_EQ(lowest, 0.5);
  const PatchMesh m = mesh_scene(s, {});
  EXPECT_EQ(m.surface_specular.size(), s.surfaces.size());
}

}  // namespace lambert

namespace lambert {

// Regressions of the review: face colours (--vertex-colors-as-reflectance) replace Kd and
// obey its rules on specular materials (0 on glass, colour + Ks <= 1 on mirrors), naming
// the face's line; an unused mirror in the library does not turn a diffuse lossless scene
// (Kd 1, a warning until F is known) into an error.
TEST(MtlSpecular, FaceColoursOnSpecularMaterialsObeyKdsRules) {
  const std::string obj =
      "mtllib s.mtl\n"
      "g floor\nusemtl white\nv 0 0 0 0.5 0.5 0.5\nv 0 0 1 0.5 0.5 0.5\nv 1 0 1 0.5 0.5 0.5\n"
      "v 1 0 0 0.5 0.5 0.5\nf 1 2 3 4\n"
      "g lamp\nusemtl lamp\nv 0 1 0\nv 1 1 0\nv 0 1 1\nf 5 6 7\n"
      "g wall\nusemtl m\nv 0 0 0 0.4 0.4 0.4\nv 0 1 0 0.4 0.4 0.4\nv 0 1 1 0.4 0.4 0.4\n"
      "v 0 0 1 0.4 0.4 0.4\nf 8 9 10 11\n";
  LoadOptions o;
  o.vertex_colors_as_reflectance = true;
  auto error = [&](const std::string& body) {
    std::istringstream in(obj);
    const std::string mtl = std::string(kMtlHead) + body;
    const MtlOpener open = [&](const std::string&) {
      return MtlFile{std::make_unique<std::istringstream>(mtl), "s.mtl"};
    };
    try {
      load_obj_stream(in, "s.obj", open, nullptr, o);
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error("Kd 0\nNi 1.5\nillum 7\n").find("s.obj:21: face colour"), std::string::npos)
      << error("Kd 0\nNi 1.5\nillum 7\n");
  EXPECT_NE(error("Kd 0\nKs 0.7\nillum 3\n").find("exceeds 1"), std::string::npos);
  EXPECT_EQ(error("Kd 0\nKs 0.6\nillum 3\n"), "");  // 0.4 + 0.6 = 1: lossless, accepted
}

TEST(MtlSpecular, UnusedMirrorKeepsADiffuseLosslessSceneAWarning) {
  const std::string obj = "mtllib s.mtl\ng a\nusemtl w\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  LoadReport report;
  EXPECT_NO_THROW(load_text(obj, "newmtl w\nKd 1 1 1\nnewmtl unused\nKs 1\nillum 3\n", &report));
  EXPECT_FALSE(report.warnings.empty());
}

}  // namespace lambert
