#pragma once
// Daylight in the radiosity problem (geometry/visibility/daylight.hpp): the sky's and the
// sun's irradiance on each patch, added to E as first-bounce sources, E_i + ρ_i (H_sky,i +
// H_sun,i), and what they bring to the report.

#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "io/json.hpp"
#include "pipeline/job.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// Per patch, the irradiance the sky and the sun bring (N x 3, W/m²; zero-sized without
/// them), and its power Σ_i A_i H_i (W per channel, areas in the scene's units²).
struct DaylightSources {
  Eigen::MatrixX3d sky;
  Eigen::MatrixX3d sun;
  Eigen::Vector3d sky_power = Eigen::Vector3d::Zero();
  Eigen::Vector3d sun_power = Eigen::Vector3d::Zero();
  /// What the patches reflect of it: ρ_i (H_sky,i + H_sun,i) (N x 3), added to E.
  Eigen::MatrixX3d reflected(const PatchMesh& mesh) const;
  /// The sun's part alone, ρ_i H_sun,i (N x 3; zeros without a sun): the renderer draws it
  /// per pixel with exact shadows instead of per patch.
  Eigen::MatrixX3d reflected_sun(const PatchMesh& mesh) const;
};

/// The sky's and the sun's irradiance on every patch of `mesh` (BVH `bvh`) over the F its
/// problem is solved with (`continued`: F's specular_continued).
DaylightSources daylight_sources(const Daylight& light, const PatchMesh& mesh, const Bvh& bvh,
                                 const SparseRowMatrix& F, const Eigen::VectorXd& continued,
                                 std::uint64_t seed, int threads);

/// The same with the patches' mean sun irradiance `sun` (N x 3) already computed.
DaylightSources daylight_sources(const Daylight& light, const PatchMesh& mesh,
                                 const SparseRowMatrix& F, const Eigen::VectorXd& continued,
                                 Eigen::MatrixX3d sun);

/// The same for a loaded scene (its daylight, and sun_patch_part's cached sun part) over the
/// F its problem is solved with.
/// Refuses (UsageError) a scene with mirrors or glass: light from outside does not follow specular
/// paths yet. Warns when the sky or the sun lights no patch. The sun's shadow rays come from
/// (`seed`, patch): bitwise the same for any thread count.
DaylightSources daylight_sources(const LoadedScene& scene, const FormFactors& F, std::uint64_t seed,
                                 int threads);

/// The patches' mean sun irradiance (N x 3), the same as daylight_sources' `sun` (zeros
/// without a sun): what render_scene takes out of B to draw the sun per pixel. Computed once
/// per mesh and seed (cached in the LoadedScene: the solve's shadow rays serve the render).
Eigen::MatrixX3d sun_patch_part(const LoadedScene& scene, std::uint64_t seed, int threads);

/// make_problem with the daylight's sources added to E (`sources` filled; empty without
/// daylight).
RadiosityProblem make_lit_problem(const LoadedScene& scene, const FormFactors& F,
                                  std::uint64_t seed, int threads, DaylightSources* sources);

/// The settings text's daylight words, " sky=R,G,B sun=DX,DY,DZ,R,G,B" ("" without it).
std::string daylight_settings_text(const Daylight& light);

/// The report's "daylight" object: the sky radiance, the sun's direction and irradiance, and
/// the power each brings to the patches. Null without daylight.
Json daylight_json(const Daylight& light, const DaylightSources& sources);

}  // namespace lambert
