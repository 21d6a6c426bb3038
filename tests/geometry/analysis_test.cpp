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
  o.samples = 4;
  o.progress = false;
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
