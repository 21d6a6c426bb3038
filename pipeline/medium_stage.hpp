#pragma once
// Participating media in a run (docs/media.md): the medium options, the medium they describe,
// and the extended solve over patches and zones (geometry/formfactors/media.hpp).

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "geometry/formfactors/analysis.hpp"
#include "geometry/formfactors/media.hpp"
#include "geometry/media/medium.hpp"
#include "geometry/render/render.hpp"
#include "io/json.hpp"
#include "pipeline/job.hpp"
#include "pipeline/render_stages.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// --medium-box, --sigma-a, --sigma-s, --medium-emission, --medium-grid, --voxels,
/// --voxel-size, --medium-rays, --transmittance-samples.
struct MediumArgs {
  std::vector<double> box;         ///< X0,Y0,Z0,X1,Y1,Z1 (empty: no homogeneous medium)
  std::vector<double> sigma_a;     ///< R,G,B (1/unit); empty = 0
  std::vector<double> sigma_s;     ///< R,G,B (1/unit); empty = 0
  std::vector<double> emission;    ///< R,G,B (W/unit³); empty = 0
  std::string grid;                ///< --medium-grid FILE (io/medium_file.hpp)
  int voxels = 16;                 ///< voxels along the box's longest axis
  double voxel_size = 0.0;         ///< > 0: cubes of about this edge instead of --voxels
  int rays = 256;                  ///< rays per patch and per zone
  int transmittance_samples = 16;  ///< point pairs per patch pair
  /// Which options the front end was given (the CLI sets it; empty = none).
  OptionGiven given;
  /// True when a medium was asked for (--medium-box or --medium-grid).
  bool active() const { return !box.empty() || !grid.empty(); }
};

/// The options "--medium-box", ...: the rows of group "medium" in pipeline/option_specs.cpp.
const std::vector<std::string>& medium_option_names();

/// The first of medium_option_names() given on the command line, or "" for none.
std::string first_medium_option_given(const MediumArgs& args);

/// The medium the options describe (null when none), validated. Throws UsageError for
/// coefficients without --medium-box, --medium-box with --medium-grid, --voxels or
/// --voxel-size with --medium-grid, a bad box or coloured extinction; SceneError/IoError
/// for a bad grid file.
std::shared_ptr<const Medium> make_medium(const MediumArgs& args);

/// Refuses (UsageError) what the medium does not combine with, naming it: specular
/// surfaces (their extended form factors are not attenuated) and, when the command renders
/// (`shade` not null), raytrace shading and --vertex-interp exact-direct (they compute light
/// without the medium).
void check_medium_scene(const PatchMesh& mesh, const ShadeArgs* shade);

/// The extended F (patches, then the zones of `medium`) from the patches' `surface` F.
FormFactors medium_form_factors(const LoadedScene& scene, const FormFactors& surface,
                                const Medium& medium, const Zones& zones, const MediumArgs& args,
                                const RunArgs& run);

/// The surface table of `extended` (medium_form_factors of `surface`) with standard errors
/// (medium_surface_factors: the medium's estimate repeated in independent replicates).
SurfaceFactors medium_surface_table(const LoadedScene& scene, const FormFactors& surface,
                                    const FormFactors& extended, const Medium& medium,
                                    const Zones& zones, const MediumArgs& args, const RunArgs& run);

/// What the extended solve produced.
struct MediumResult {
  std::shared_ptr<const Medium> medium;
  Zones zones;
  FormFactorStats stats;     ///< of the extended F (rays include the surface estimator's)
  std::int64_t entries = 0;  ///< stored entries of the extended F
  double seconds = 0.0;      ///< the medium's exchange factors
  bool loaded = false;       ///< they came with a loaded F (--ff)
  int rays = 0, transmittance_samples = 0;  ///< their settings (the file's when loaded)
  /// Per channel: power absorbed by the surfaces and by the medium (W); together they are
  /// the energy balance's `absorbed`.
  std::array<double, 3> absorbed_surfaces{}, absorbed_medium{};
  MediumView view;  ///< the per-voxel radiosity for rendering
};

/// Extends `surface` (the patches' F) with the medium's zones (unless it holds them already:
/// a loaded extended F, checked by obtain_form_factors), solves the extended system
/// and fills `r` (B: the patches' rows only; solution: every unknown; indirect: empty, since
/// exact-direct vertices are refused with a medium) and the returned result.
MediumResult solve_scene_with_medium(const LoadedScene& scene, const FormFactors& surface,
                                     std::shared_ptr<const Medium> medium, const MediumArgs& args,
                                     const SolveOptions& solver, const RunArgs& run,
                                     RadiosityResult& r);

/// The report section: {source, bounds, resolution, zones, rays_per_unknown,
/// transmittance_samples, loaded, entries, seconds, absorbed_surfaces [R,G,B],
/// absorbed_medium [R,G,B]}.
Json medium_json(const MediumResult& m);

/// One line of key=value text for metadata: "medium=SOURCE voxels=NXxNYxNZ medium_rays=K
/// transmittance_samples=S".
std::string medium_settings_text(const MediumResult& m);

}  // namespace lambert
