// find_lighting_problems: scenes that cannot work (inside out, a light facing away, no
// light) are found from the mesh and F alone.

#include "geometry/formfactors/analysis.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "geometry/analytic.hpp"

namespace lambert {
namespace {

// Reverses the winding of the faces of `surface` (all surfaces when empty).
Scene inverted(Scene s, const std::string& surface = "") {
  for (Face& f : s.faces)
    if (surface.empty() || s.surfaces[f.surface].name == surface)
      std::reverse(f.vertices.begin(), f.vertices.end());
  return s;
}

// Few rays suffice: only which entries are zero matters here.
SparseF form_factors(const PatchMesh& mesh) {
  FormFactorOptions o;
  o.pair.samples = 4;
  o.run.progress = false;
  return compute_form_factors(mesh, o).F;
}

std::int32_t surface_index(const PatchMesh& mesh, const std::string& name) {
  const auto it = std::find(mesh.surface_names.begin(), mesh.surface_names.end(), name);
  return static_cast<std::int32_t>(it - mesh.surface_names.begin());
}

bool mentions(const std::vector<std::string>& lines, const std::string& text) {
  return std::any_of(lines.begin(), lines.end(),
                     [&](const std::string& l) { return l.find(text) != std::string::npos; });
}

}  // namespace

TEST(LightingProblems, TheUnitCubeHasNone) {
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.5, 0});
  const LightingProblems p = find_lighting_problems(mesh, form_factors(mesh));
  EXPECT_FALSE(p.any());
  EXPECT_TRUE(lighting_warnings(mesh, p).empty());
}

TEST(LightingProblems, AnInsideOutCubeSeesNothingAndSaysSoOnce) {
  const PatchMesh mesh = mesh_scene(inverted(unit_cube()), {0.5, 0});
  const LightingProblems p = find_lighting_problems(mesh, form_factors(mesh));
  EXPECT_TRUE(p.nothing_visible);
  EXPECT_EQ(p.pairs, std::int64_t{mesh.size()} * (mesh.size() - 1) / 2);
  EXPECT_FALSE(p.no_emitter);
  // The lamp sees nothing too, but for the same reason: one warning, not two.
  EXPECT_TRUE(p.blind_emitters.empty());
  const auto lines = lighting_warnings(mesh, p);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(mentions(lines, "inside out")) << lines[0];
  EXPECT_TRUE(mentions(lines, std::to_string(p.pairs) + " patch pairs")) << lines[0];
}

TEST(LightingProblems, ALampFacingOutOfTheCubeIsNamed) {
  const PatchMesh mesh = mesh_scene(inverted(unit_cube(), "+y"), {0.5, 0});
  const LightingProblems p = find_lighting_problems(mesh, form_factors(mesh));
  EXPECT_FALSE(p.nothing_visible);
  EXPECT_FALSE(p.no_emitter);
  EXPECT_EQ(p.blind_emitters, std::vector<std::int32_t>{surface_index(mesh, "+y")});
  const auto lines = lighting_warnings(mesh, p);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(mentions(lines, "emitter '+y' sees nothing")) << lines[0];
}

TEST(LightingProblems, ATinyButNonzeroRowIsNotBlind) {
  // Every lamp row sums to 1e-300 (one entry, to patch 0 or 1): the lamp does see something.
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.5, 0});
  const std::int32_t lamp = surface_index(mesh, "+y");
  SparseF F(mesh.size(), mesh.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    if (mesh.patches[i].surface == lamp) F.insert(i, i == 0 ? 1 : 0) = 1e-300;
  const LightingProblems p = find_lighting_problems(mesh, F);
  EXPECT_FALSE(p.nothing_visible);
  EXPECT_TRUE(p.blind_emitters.empty());
}

TEST(LightingProblems, ASceneWithoutEmitterIsReported) {
  PatchMesh mesh = mesh_scene(unit_cube(), {0.5, 0});
  for (Patch& patch : mesh.patches) patch.emission.setZero();
  const LightingProblems p = find_lighting_problems(mesh, form_factors(mesh));
  EXPECT_TRUE(p.no_emitter);
  EXPECT_FALSE(p.nothing_visible);
  EXPECT_TRUE(p.blind_emitters.empty());
  const auto lines = lighting_warnings(mesh, p);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(mentions(lines, "no surface emits")) << lines[0];
}

}  // namespace lambert

namespace lambert {
namespace {

// A mesh of `rho.size()` patches, patch i on surface "s<i>", with an F given by triplets
// (only the sizes, rho and surfaces matter to find_closed_lossless).
struct TinySystem {
  PatchMesh mesh;
  FormFactors ff;
};

TinySystem tiny(const std::vector<double>& rho,
                const std::vector<Eigen::Triplet<double, std::int32_t>>& entries) {
  TinySystem t;
  const auto n = static_cast<std::int32_t>(rho.size());
  for (std::int32_t i = 0; i < n; ++i) {
    Patch p;
    p.area = 1.0;
    p.rho = Eigen::Vector3d(rho[i], rho[i], 0.5);  // B is never lossless
    p.surface = i;
    t.mesh.patches.push_back(p);
    t.mesh.surface_names.push_back("s" + std::to_string(i));
  }
  t.ff.F.resize(n, n);
  t.ff.F.setFromTriplets(entries.begin(), entries.end());
  return t;
}

}  // namespace

// Patches 0 and 1 are lossless and exchange all their light; 2 is lossless but leaks into
// 3, which absorbs: only {0, 1} is closed, in R and G but not B.
TEST(ClosedLossless, FindsTheClosedSetAndItsChannels) {
  const TinySystem t = tiny({1, 1, 1, 0.5}, {{0, 1, 1.0}, {1, 0, 1.0}, {2, 3, 0.5}, {2, 0, 0.5},
                                             {3, 2, 1.0}});
  const auto sets = find_closed_lossless(t.mesh, t.ff);
  ASSERT_EQ(sets.size(), 1u);
  EXPECT_EQ(sets[0].patches, (std::vector<std::int32_t>{0, 1}));
  EXPECT_EQ(sets[0].channels, (std::vector<int>{0, 1}));
  EXPECT_NE(closed_lossless_message(t.mesh, sets[0])
                .find("surfaces 's0', 's1' (2 patches) are lossless (reflectance 1) in channel R, G"),
            std::string::npos);
}

// 0 sends everything to 1, 1 sends half back to 0 and half to the absorbing 2: 1 leaks,
// and once it is dropped so does 0 (all of its light reaches a leaking patch).
TEST(ClosedLossless, LeaksPropagateThroughTheSet) {
  const TinySystem t = tiny({1, 1, 0.5}, {{0, 1, 1.0}, {1, 0, 0.5}, {1, 2, 0.5}, {2, 1, 1.0}});
  EXPECT_TRUE(find_closed_lossless(t.mesh, t.ff).empty());
}

// A leak of 1e-4 per row is real without stderr (above kClosedRowTolerance = 1e-6) but
// within 5 row standard errors of 1e-4 each: F cannot tell that set from a closed one.
TEST(ClosedLossless, ALeakWithinFsStandardErrorCountsAsClosed) {
  TinySystem t = tiny({1, 1}, {{0, 1, 1.0 - 1e-4}, {1, 0, 1.0 - 1e-4}});
  EXPECT_TRUE(find_closed_lossless(t.mesh, t.ff).empty());
  t.ff.stderr_F = t.ff.F;
  t.ff.stderr_F.coeffs().setConstant(1e-4);
  ASSERT_EQ(find_closed_lossless(t.mesh, t.ff).size(), 1u);
}

// The closed unit cube with rho = 1 everywhere is singular; one face at 0.5 or one face
// removed (light escapes) is not. Hybrid's unoccluded cube is exact to quadrature, 1e-6.
TEST(ClosedLossless, TheLosslessUnitCubeIsClosedUnlessAFaceAbsorbsOrIsMissing) {
  Scene s = unit_cube();
  for (Material& m : s.materials) m.rho.setOnes();
  MeshOptions mo;
  mo.max_edge = 0.5;
  FormFactors ff;
  PatchMesh mesh = mesh_scene(s, mo);
  ff.F = form_factors(mesh);
  const auto sets = find_closed_lossless(mesh, ff);
  ASSERT_EQ(sets.size(), 1u);
  EXPECT_EQ(sets[0].patches.size(), 24u);
  EXPECT_EQ(sets[0].surfaces.size(), 6u);
  EXPECT_EQ(sets[0].channels, (std::vector<int>{0, 1, 2}));
  for (Patch& p : mesh.patches)
    if (mesh.surface_names[p.surface] == "-y") p.rho[1] = 0.5;  // absorbs in G only
  const auto absorbing = find_closed_lossless(mesh, ff);
  ASSERT_EQ(absorbing.size(), 1u);
  EXPECT_EQ(absorbing[0].channels, (std::vector<int>{0, 2}));
  Scene open = s;
  open.faces.erase(std::remove_if(open.faces.begin(), open.faces.end(),
                                  [&](const Face& f) { return open.surfaces[f.surface].name == "+z"; }),
                   open.faces.end());
  const PatchMesh open_mesh = mesh_scene(open, mo);
  FormFactors open_ff;
  open_ff.F = form_factors(open_mesh);
  EXPECT_TRUE(find_closed_lossless(open_mesh, open_ff).empty());
}

}  // namespace lambert
