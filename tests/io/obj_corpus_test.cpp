// The OBJ corpus of tests/data/obj/ (issue 20): each file exercises one case of what real
// files hold; each test asserts surface names, areas and materials, or the exact warning,
// and that --strict turns a default into an error.
#include <gtest/gtest.h>

#include <map>
#include <sstream>

#include "core/error.hpp"
#include "geometry/mesh/mesh.hpp"
#include "geometry/polygon.hpp"
#include "io/obj_loader.hpp"

namespace lambert {
namespace {

std::string corpus(const std::string& name) {
  return std::string(LAMBERT_TEST_CORPUS_DIR) + "/obj/" + name;
}

// Surface name -> (material name, area).
std::map<std::string, std::pair<std::string, double>> surfaces(const Scene& s) {
  std::map<std::string, std::pair<std::string, double>> out;
  for (size_t k = 0; k < s.surfaces.size(); ++k) out[s.surfaces[k].name].first = s.material_of(k).name;
  std::vector<Eigen::Vector3d> poly;
  for (const auto& f : s.faces) {
    poly.clear();
    for (auto v : f.vertices) poly.push_back(s.vertices[v]);
    out[s.surfaces[f.surface].name].second += polygon_area(poly);
  }
  return out;
}

// Loads a corpus file; returns its scene and report.
Scene load(const std::string& name, LoadReport& report, LoadOptions options = {}) {
  return load_obj(corpus(name), &report, options);
}

// The error loading a corpus file (with --strict if asked); "" if it loads.
std::string error_of(const std::string& name, bool strict = false) {
  LoadOptions o;
  o.strict = strict;
  try {
    load_obj(corpus(name), nullptr, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

bool has_warning(const LoadReport& r, const std::string& w) {
  for (const auto& x : r.warnings)
    if (x == w) return true;
  ADD_FAILURE() << "no warning '" << w << "' among:\n" << [&] {
    std::string all;
    for (const auto& x : r.warnings) all += "  " + x + "\n";
    return all;
  }();
  return false;
}

const std::string kDefault =
    "the default material (rho 0.5 0.5 0.5, no emission; --default-reflectance R,G,B)";

}  // namespace

// A defaulted case: loads `file` with the warning `line: what: surface(s) 'surface' use
// the default...` and, with --strict, fails with `line: refusal`; returns surface -> material.
std::map<std::string, std::string> expect_defaulted(const std::string& file, const std::string& what,
                                                    const std::string& surface,
                                                    const std::string& refusal) {
  LoadReport r;
  const Scene s = load(file, r);
  const std::string at = corpus(file) + ":";
  EXPECT_TRUE(has_warning(r, at + what + ": surface(s) '" + surface + "' use " + kDefault));
  EXPECT_EQ(error_of(file, true), at + refusal);
  std::map<std::string, std::string> out;
  for (const auto& [name, m] : surfaces(s)) out[name] = m.first;
  return out;
}

TEST(ObjCorpus, NoMtllibGivesTheDefaultMaterialWithOneWarning) {
  const auto m = expect_defaulted("no_mtllib.obj", "7: faces without usemtl (and no mtllib)", "floor",
                                  "7: face has no material (no usemtl before it)");
  EXPECT_EQ(m.at("floor"), "default");
  LoadReport r;
  EXPECT_EQ(load("no_mtllib.obj", r).material_of(0).rho, Eigen::Vector3d::Constant(0.5));
}

TEST(ObjCorpus, DefaultReflectanceIsAnOption) {
  LoadReport r;
  LoadOptions o;
  o.default_reflectance = {0.1, 0.2, 0.3};
  const Scene s = load("no_mtllib.obj", r, o);
  EXPECT_EQ(s.material_of(0).rho, Eigen::Vector3d(0.1, 0.2, 0.3));
}

TEST(ObjCorpus, MissingMaterialLibraryIsAWarningNamingItsLine) {
  const auto m = expect_defaulted("missing_mtllib.obj", "7: material 'white' is not defined in the material library",
                                  "floor", "1: material library 'nothere.mtl' not found");
  EXPECT_EQ(m.at("floor"), "white");
  LoadReport r;
  load("missing_mtllib.obj", r);
  EXPECT_TRUE(has_warning(r, corpus("missing_mtllib.obj") + ":1: material library 'nothere.mtl' not found: the materials it would define get the default"));
}

TEST(ObjCorpus, UndefinedMaterialIsDefaultedOncePerName) {
  const auto m = expect_defaulted("undefined_material.obj", "10: material 'glow' is not defined in the material library",
                                  "lamp", "10: material 'glow' is not defined in the material library");
  EXPECT_EQ(m.at("floor"), "white");
  EXPECT_EQ(m.at("lamp"), "glow");
}

TEST(ObjCorpus, UsemtlWithoutANameIsDefaulted) {
  const auto m = expect_defaulted("empty_usemtl.obj", "7: usemtl without a material name", "floor",
                                  "7: usemtl without a material name");
  EXPECT_EQ(m.at("floor"), "default");
}

TEST(ObjCorpus, FacesBeforeAnyUsemtlAreDefaulted) {
  const auto m = expect_defaulted("faces_before_usemtl.obj", "7: faces without usemtl", "floor",
                                  "7: face has no material (no usemtl before it)");
  EXPECT_EQ(m.at("floor"), "default");
  EXPECT_EQ(m.at("wall"), "white");
}

TEST(ObjCorpus, MaterialNamesWithSpacesResolveTrimmed) {
  LoadReport r;
  const Scene s = load("spaces_in_names.obj", r);
  const auto surf = surfaces(s);
  EXPECT_EQ(surf.at("floor").first, "Hard Shiny Plastic White");
  EXPECT_EQ(surf.at("lamp").first, "Warm Light");
  EXPECT_DOUBLE_EQ(s.material_of(1).emission[0], 5.0);
  EXPECT_TRUE(r.has_emitter);
  EXPECT_EQ(error_of("spaces_in_names.obj", true), "");
}

TEST(ObjCorpus, ReflectanceOneIsAcceptedWithAWarningAndClampedOnRequest) {
  LoadReport r;
  const Scene s = load("kd_one.obj", r);
  EXPECT_EQ(surfaces(s).at("floor").first, "mirrorish");
  EXPECT_EQ(s.material_of(0).rho, Eigen::Vector3d::Ones());
  EXPECT_TRUE(has_warning(r, corpus("kd_one.obj") + ": material(s) 'mirrorish' have reflectance 1 in some channel (lossless): the radiosity system is singular if such surfaces enclose a space where nothing absorbs, which is refused once form factors are known; --max-reflectance 0.99 clamps"));
  EXPECT_NE(error_of("kd_one.obj", true).find("kd_one.mtl:2: material 'mirrorish': reflectance Kd 1 1 1 must lie in [0, 1)"), std::string::npos);
  LoadOptions o;
  o.max_reflectance = 0.99;
  LoadReport rc;
  const Scene c = load("kd_one.obj", rc, o);
  EXPECT_EQ(c.material_of(0).rho, Eigen::Vector3d::Constant(0.99));
  EXPECT_EQ(c.material_of(1).rho, Eigen::Vector3d::Constant(0.5));
  EXPECT_TRUE(has_warning(rc, corpus("kd_one.obj") + ": Kd clamped to --max-reflectance 0.99 in material(s) 'mirrorish'"));
}

TEST(ObjCorpus, UnusedStatementsAreSkippedWithOneSummary) {
  LoadReport r;
  const Scene s = load("skipped.obj", r);
  EXPECT_DOUBLE_EQ(surfaces(s).at("floor").second, 1.0);
  EXPECT_EQ(r.skipped_statements, 15);
  EXPECT_TRUE(has_warning(r, corpus("skipped.obj") +
      ": skipped what radiosity does not use: 1 bevel (first at line 22), 1 cstype (first at line 11), "
      "1 curv (first at line 13), 1 deg (first at line 12), 1 end (first at line 15), 1 l (first at line 17), "
      "1 lod (first at line 21), 1 mg (first at line 20), 1 p (first at line 16), 1 parm (first at line 14), "
      "1 s (first at line 19), 1 vn (first at line 9), 1 vp (first at line 10), 2 vt (first at line 7)"));
  EXPECT_EQ(error_of("skipped.obj", true), "");
}

TEST(ObjCorpus, VertexColoursAreAcceptedAndSkipped) {
  LoadReport r;
  const Scene s = load("vertex_colors.obj", r);
  EXPECT_DOUBLE_EQ(surfaces(s).at("floor").second, 1.0);
  EXPECT_EQ(s.vertices[1], Eigen::Vector3d(1, 0, 0));
  EXPECT_TRUE(has_warning(r, corpus("vertex_colors.obj") + ": skipped what radiosity does not use: 4 vertex colours (first at line 2)"));
}

// Per-face means of corner colours are sums of four doubles divided by 4: each operation
// rounds by at most 2^-53 relative of values <= 1, so 5 roundings stay below 1e-15.
constexpr double kMeanRounding = 1e-15;

// Patch reflectances of a scene meshed into 0.5-sized patches, per (surface, x > 1 side).
std::map<std::pair<std::string, bool>, std::vector<Eigen::Vector3d>> patch_rho(const Scene& s) {
  MeshOptions mo;
  mo.max_edge = 0.5;
  const PatchMesh m = mesh_scene(s, mo);
  std::map<std::pair<std::string, bool>, std::vector<Eigen::Vector3d>> out;
  for (const auto& p : m.patches)
    out[{m.surface_names[p.surface], p.centroid.x() > 1}].push_back(p.rho);
  return out;
}

void expect_all_near(const std::vector<Eigen::Vector3d>& rhos, const Eigen::Vector3d& want) {
  ASSERT_FALSE(rhos.empty());
  for (const auto& r : rhos)
    EXPECT_LT((r - want).cwiseAbs().maxCoeff(), kMeanRounding) << r.transpose();
}

TEST(ObjCorpus, VertexColoursBecomePerFaceReflectanceOfThePatches) {
  LoadReport r;
  LoadOptions o;
  o.vertex_colors_as_reflectance = true;
  const Scene s = load("vertex_colors_reflectance.obj", r, o);
  ASSERT_EQ(s.surfaces.size(), 3u);  // colours split no surface
  const auto rho = patch_rho(s);
  expect_all_near(rho.at({"floor", false}), Eigen::Vector3d(0.3, 0.4, 0.4));
  expect_all_near(rho.at({"floor", true}), Eigen::Vector3d(0.55, 0.2, 0.2));
  expect_all_near(rho.at({"wall", false}), Eigen::Vector3d::Constant(0.7));  // white's Kd
  expect_all_near(rho.at({"edge", false}), Eigen::Vector3d::Constant(0.7));
  EXPECT_TRUE(has_warning(r, corpus("vertex_colors_reflectance.obj") +
      ":23: faces with colours on only some corners keep their material's Kd: surface(s) 'edge'"));
  for (const auto& w : r.warnings) EXPECT_EQ(w.find("skipped"), std::string::npos) << w;
  // Without the option the colours are skipped and every patch reflects Kd.
  LoadReport plain;
  for (const auto& [key, rhos] : patch_rho(load("vertex_colors_reflectance.obj", plain)))
    expect_all_near(rhos, Eigen::Vector3d::Constant(0.7));
}

TEST(ObjCorpus, VertexColoursIn0To255AreScaledWithAWarningOrRefusedWhenStrict) {
  LoadReport r;
  LoadOptions o;
  o.vertex_colors_as_reflectance = true;
  const Scene s = load("vertex_colors_255.obj", r, o);
  expect_all_near(patch_rho(s).at({"floor", false}), Eigen::Vector3d(0.5, 0.3, 0.5));
  const std::string at = corpus("vertex_colors_255.obj") + ":3: vertex colour component 255 is above 1";
  EXPECT_TRUE(has_warning(r, at + ": the file's colours are read as 0..255 and divided by 255"));
  o.strict = true;
  try {
    load("vertex_colors_255.obj", r, o);
    ADD_FAILURE() << "--strict loaded 0..255 colours";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()), at + ": a reflectance lies in [0, 1]; rescale the colours");
  }
}

TEST(ObjCorpus, VertexColourOfOneIsLosslessAndClampedByMaxReflectance) {
  LoadOptions o;
  o.vertex_colors_as_reflectance = true;
  LoadReport r;
  const Scene s = load("vertex_colors.obj", r, o);  // corner colours mean (0.5, 0.5, 0.5)...
  expect_all_near(patch_rho(s).at({"floor", false}), Eigen::Vector3d::Constant(0.5));
  // ...and a face whose corners are all white reflects 1: warned about, clamped on request.
  LoadReport w;
  const std::string white = "v 0 0 0 1 1 1\nv 1 0 0 1 1 1\nv 1 0 1 1 1 1\nf 1 3 2\n";
  std::istringstream in(white);
  const MtlOpener none = [](const std::string&) { return MtlFile{}; };
  load_obj_stream(in, "w.obj", none, &w, o);
  EXPECT_TRUE(has_warning(w, "w.obj: vertex colours of surface(s) 'default' have reflectance 1 in "
      "some channel (lossless): the radiosity system is singular if such surfaces enclose a "
      "space where nothing absorbs (here every surface is lossless in one channel), which is "
      "refused once form factors are known; --max-reflectance 0.99 clamps"));
  o.max_reflectance = 0.99;
  std::istringstream in2(white);
  const Scene c = load_obj_stream(in2, "w.obj", none, &w, o);
  ASSERT_TRUE(c.faces[0].rho.has_value());
  EXPECT_EQ(*c.faces[0].rho, Eigen::Vector3d::Constant(0.99));
  EXPECT_TRUE(has_warning(w, "w.obj: vertex-colour reflectance clamped to --max-reflectance 0.99 on surface(s) 'default'"));
}

TEST(ObjCorpus, VertexColoursOutsideZeroOneThatAreNot0To255AreRefused) {
  LoadOptions o;
  o.vertex_colors_as_reflectance = true;
  const MtlOpener none = [](const std::string&) { return MtlFile{}; };
  auto error = [&](const std::string& text) {
    std::istringstream in(text);
    try {
      load_obj_stream(in, "c.obj", none, nullptr, o);
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error("v 0 0 0 0 0 0\nv 1 0 0 1.5 0 0\nv 1 0 1 0 0 0\nf 1 3 2\n"),
            "c.obj:2: vertex colour component 1.5 is above 1: a reflectance lies in [0, 1] "
            "(colours in 0..255 are read when all are whole numbers); rescale the colours");
  EXPECT_EQ(error("v 0 0 0 0 0 0\nv 1 0 0 0 -0.5 0\nv 1 0 1 0 0 0\nf 1 3 2\n"),
            "c.obj:2: vertex colour component -0.5 is negative: a reflectance lies in [0, 1]");
  EXPECT_EQ(error("v 0 0 0 0 0 0\nv 1 0 0 256 0 0\nv 1 0 1 0 0 0\nf 1 3 2\n").substr(0, 40),
            "c.obj:2: vertex colour component 256 is ");
}

TEST(ObjCorpus, Utf8ByteOrderMarkIsSkippedAndUtf16Refused) {
  LoadReport r;
  EXPECT_DOUBLE_EQ(surfaces(load("bom.obj", r)).at("floor").second, 1.0);
  EXPECT_EQ(error_of("utf16.obj"), corpus("utf16.obj") + ": UTF-16 text: convert to UTF-8");
}

TEST(ObjCorpus, LastLineWithoutNewlineAndEveryLineEndingWork) {
  LoadReport r;
  for (const char* f : {"no_final_newline.obj", "mixed_line_endings.obj", "formfeed_vtab.obj"}) {
    const Scene s = load(f, r);
    ASSERT_EQ(s.faces.size(), 1u) << f;
    EXPECT_EQ(s.faces[0].vertices.size(), 4u) << f;
    EXPECT_DOUBLE_EQ(surfaces(s).at("floor").second, 1.0) << f;
    EXPECT_EQ(s.material_of(0).name, "white") << f;
  }
}

TEST(ObjCorpus, GroupsWithSeveralNamesRepeatedGroupsAndSeveralMaterials) {
  LoadReport r;
  const Scene s = load("groups.obj", r);
  const auto surf = surfaces(s);
  ASSERT_EQ(s.surfaces.size(), 4u);
  EXPECT_EQ(s.surfaces[0].name, "left wall");
  EXPECT_EQ(s.surfaces[1].name, "floor/white");
  EXPECT_EQ(s.surfaces[2].name, "ceiling");
  EXPECT_EQ(s.surfaces[3].name, "floor/red");
  EXPECT_DOUBLE_EQ(surf.at("left wall").second, 1.0);
  EXPECT_DOUBLE_EQ(surf.at("floor/white").second, 1.5);  // the repeated group's face appended
  EXPECT_DOUBLE_EQ(surf.at("ceiling").second, 0.5);
  EXPECT_DOUBLE_EQ(surf.at("floor/red").second, 1.0);
  EXPECT_EQ(surf.at("floor/red").first, "red");
}

TEST(ObjCorpus, WindowsPathInMtllibFindsTheLibraryNextToTheObj) {
  LoadReport r;
  const Scene s = load("windows_mtllib_path.obj", r);
  EXPECT_EQ(s.material_of(0).rho, Eigen::Vector3d::Constant(0.7));
  EXPECT_EQ(error_of("windows_mtllib_path.obj", true), "");
}

TEST(ObjCorpus, CoincidentDuplicateFacesAreWarnedAboutNamingBothSurfaces) {
  LoadReport r;
  load("duplicate_faces.obj", r);
  EXPECT_EQ(r.coincident_faces, 1);
  EXPECT_TRUE(has_warning(r, corpus("duplicate_faces.obj") + ":10: face coincides with the face at line 8 (surfaces 'floor' and 'floor copy', 1 coincident face(s)): its area counts twice"));
}

TEST(ObjCorpus, BlenderExportLoadsWithNamesAreasAndTheLight) {
  LoadReport r;
  const Scene s = load("blender_room.obj", r);
  const auto surf = surfaces(s);
  ASSERT_EQ(surf.size(), 4u);
  EXPECT_EQ(surf.at("Room/Walls").first, "Walls");
  EXPECT_DOUBLE_EQ(surf.at("Room/Walls").second, 20.0);
  EXPECT_DOUBLE_EQ(surf.at("Room/Red").second, 4.0);
  EXPECT_DOUBLE_EQ(surf.at("Cube").second, 1.5);
  EXPECT_DOUBLE_EQ(surf.at("Light").second, 0.25);
  EXPECT_EQ(s.material_of(3).emission, Eigen::Vector3d::Constant(10));
  EXPECT_TRUE(r.has_emitter);
  ASSERT_EQ(r.warnings.size(), 1u) << r.warnings[0];
  EXPECT_EQ(r.warnings[0], corpus("blender_room.obj") +
      ": skipped what radiosity does not use: 5 s (first at line 24), 7 vn (first at line 17), 4 vt (first at line 13)");
  EXPECT_EQ(error_of("blender_room.obj", true), "");
}

TEST(ObjCorpus, EmitRulesLightSurfacesOrMaterialsByNameOrGlob) {
  LoadOptions o;
  o.emit = {{"Cube", {1, 2, 3}}, {"Room/R*", {4, 4, 4}}};
  LoadReport r;
  const Scene s = load("blender_room.obj", r, o);
  std::map<std::string, Eigen::Vector3d> e;
  for (size_t k = 0; k < s.surfaces.size(); ++k) e[s.surfaces[k].name] = s.material_of(k).emission;
  EXPECT_EQ(e.at("Cube"), Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(e.at("Room/Red"), Eigen::Vector3d::Constant(4));
  EXPECT_EQ(e.at("Room/Walls"), Eigen::Vector3d::Zero());
  EXPECT_EQ(e.at("Light"), Eigen::Vector3d::Constant(10));
  // By material name: every surface of Walls; a shared material is copied for one surface.
  o.emit = {{"Walls", {1, 1, 1}}};
  const Scene w = load("blender_room.obj", r, o);
  EXPECT_EQ(surfaces(w).at("Room/Walls").first, "Walls");
  EXPECT_EQ(w.material_of(0).emission, Eigen::Vector3d::Ones());
  o.emit = {{"nothing*", {1, 1, 1}}};
  EXPECT_THROW(load("blender_room.obj", r, o), UsageError);
}

TEST(ObjCorpus, NoEmitterWarningSaysHowToAddOne) {
  LoadReport r;
  load("no_mtllib.obj", r);
  EXPECT_FALSE(r.has_emitter);
  EXPECT_TRUE(has_warning(r, corpus("no_mtllib.obj") + ": no emitter (no material with Ke > 0): the radiosity is zero; add one with --emit SURFACE_OR_MATERIAL=R,G,B (lambert info lists the names)"));
  LoadOptions o;
  o.emit = {{"floor", {1, 1, 1}}};
  load("no_mtllib.obj", r, o);
  EXPECT_TRUE(r.has_emitter);
}

TEST(ObjCorpus, BadInputFailsWithFileAndLine) {
  EXPECT_EQ(error_of("lone_cr_index.obj"), corpus("lone_cr_index.obj") + ":2: face index 9000 out of range (1 vertices defined so far)");
  EXPECT_EQ(error_of("malformed_number.obj"), corpus("malformed_number.obj") + ":2: malformed vertex: '3.1+e2' is not a number");
  EXPECT_EQ(error_of("hex_float.obj"), corpus("hex_float.obj") + ":2: malformed vertex: '0x1p3' is not a number");
  EXPECT_EQ(error_of("huge_coordinates.obj"), corpus("huge_coordinates.obj") + ":2: vertex coordinate '1e150' is beyond +-1e50, where areas and form factors overflow: rescale the scene");
}

}  // namespace lambert
