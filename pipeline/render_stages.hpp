#pragma once
// The stages `lambert render` and `lambert run` share after load-and-mesh: radiosity (from a
// CSV or from F + solve), per-vertex reconstruction, rendering and writing the result files,
// with the options that steer them (solver options: pipeline/solve_stage.hpp).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"
#include "geometry/render/render.hpp"
#include "geometry/render/vertex_field.hpp"
#include "io/json.hpp"
#include "pipeline/daylight_stage.hpp"
#include "pipeline/ff_stage.hpp"
#include "pipeline/job.hpp"
#include "pipeline/relight.hpp"
#include "solvers/radiosity.hpp"

namespace lambert {

/// --eye, --look-at, --up, --fov, --size: overrides of the scene's default camera.
struct CameraArgs {
  std::vector<double> eye, look_at, up;  ///< 3 values each, or empty
  double fov = 0.0;                      ///< vertical field of view in degrees; 0 = the scene's
  std::string size;                      ///< "WxH"; empty = the scene camera's
  /// --view front|three-quarter|top: the scene's bounding box framed so instead of the
  /// scene's camera (view_camera); empty = the scene's camera.
  std::string view;
};
/// Scenes above this many faces are not probed by encloses_its_centre (26 rays against every
/// face: ~0.1 s at this size; a room users model is far smaller).
constexpr std::size_t kMaxEnclosureFaces = 200000;
/// True when the centre of the scene's bounding box sees the front of a face along each of
/// the 26 directions to the box's corners, edges and faces: a closed room, which a view from
/// outside would show as the backs of its walls (black). O(26 faces), no BVH.
bool encloses_its_centre(const Scene& scene);
/// The scene's camera (or one framing the scene) with the overrides applied; a default view
/// of a closed room (encloses_its_centre) is replaced by a view from inside (room_camera).
/// Throws UsageError for a malformed --size or a degenerate view.
Camera make_camera(const Scene& scene, const CameraArgs& args);

/// --shading, --flat, --final-gather, --wireframe, --antialias, --exposure, --vertex-interp.
struct ShadeArgs {
  std::string shading;     ///< gouraud, flat or raytrace; empty = from --flat / --final-gather
  bool flat = false;       ///< --flat: alias of --shading flat
  int final_gather = 0;    ///< --final-gather N: gather rays per diffuse hit (implies raytrace)
  bool wireframe = false;  ///< --wireframe: patch edges drawn over the shading
  int antialias = 2;
  std::string exposure = "auto";  ///< "auto" or EV stops
  /// auto (exact-direct on a --discontinuity mesh with F, linear on an --adapt mesh, else
  /// conservative), conservative, area, linear or exact-direct (geometry/render/vertex_field.hpp)
  std::string vertex_interp = "auto";
  /// --direct-rays N: shadow rays per pixel sample for the emitters' direct light, drawn per
  /// pixel on Gouraud images (geometry/render/pixel_direct.hpp); 0 = from the vertices like
  /// the rest; -1 = not given: kDefaultDirectRays where it applies (pixel_direct_obstacle).
  int direct_rays = -1;
};
/// Shadow rays per pixel sample for the direct light when --direct-rays is not given: 32 a
/// pixel with the default 2x2 samples (a penumbra pixel's standard error at most 1/11 of its
/// direct light, ~1.6 s of CPU on the default Cornell image; lit and umbra pixels exact).
constexpr int kDefaultDirectRays = 8;
/// The shading the options ask for: --shading, else flat with --flat, raytrace with
/// --final-gather, else Gouraud. Throws UsageError when they contradict each other.
Shading resolve_shading(const ShadeArgs& args);
/// The choices of a command that solves and renders (run, render) for the option check
/// (pipeline/option_scope.hpp): the estimator and `solver` when it computes F and solves
/// (`solves`), the shading the options resolve to, and whether pixels draw random numbers.
Selection render_selection(const std::string& command, const std::string& method, bool solves,
                           const FormFactorArgs& ff, const std::string& solver,
                           const ShadeArgs& shade, bool medium);

/// "gouraud", "flat" or "raytrace".
const char* shading_name(Shading shading);
/// The shading part of a settings line: "shading=S" and, raytraced, " specular_depth=D" and
/// " final_gather=N" (0 = off).
std::string shading_settings(const ShadeArgs& args, int specular_depth);
/// The same for a report: {shading, final_gather (0 = off), specular_depth (null unless
/// raytraced)}.
Json shading_json(const ShadeArgs& args, int specular_depth);
/// Refuses --vertex-interp exact-direct before any work when B will not come with its F
/// (`has_form_factors` false: --radiosity, --method hierarchical). Throws UsageError.
void check_vertex_interp(const ShadeArgs& args, bool has_form_factors, const std::string& why);

/// The radiosity B of every patch and how it was obtained.
struct RadiosityResult {
  Eigen::MatrixX3d B;            ///< N x 3
  bool solved = false;           ///< false when read from a CSV
  RadiositySolution solution;    ///< valid when solved
  FormFactorStats ff_stats;      ///< valid when solved (rays 0 when F was loaded)
  FormFactorOptions ff_options;  ///< valid when solved: the settings that made F (a loaded
                                 ///< file's own; see obtain_form_factors)
  /// I = F (B - E) per patch (N x 3) when solved (problem.hpp), for exact-direct vertices.
  Eigen::MatrixX3d indirect;
  DaylightSources daylight;  ///< when solved: what the sky and the sun brought (daylight_stage)
  /// When asked for: the solution per light source (relight.hpp), and their solves' time.
  std::vector<EmitterBasis> bases;
  double bases_seconds = 0.0;
  std::int64_t ff_entries = 0;
  double ff_seconds = 0.0;
  double solve_seconds = 0.0;
};

/// Records F's statistics in `r` and solves for B over F (fills B, solution, solve_seconds);
/// logs one line on stderr, and a warning when the solver did not converge. With `bases`, also
/// solves the per-emitter bases (r.bases, r.bases_seconds; relight.hpp).
void solve_scene(const LoadedScene& scene, const FormFactors& F, const SolveOptions& solver,
                 const RunArgs& run, RadiosityResult& r, bool bases = false);

/// Above this share of the emitted power, the energy that F's non-reciprocity loses or makes
/// is a warning: an averaged or symmetric estimator stays at rounding (1e-15), the hemicube on
/// the Cornell box at 8.7e-4 (its aliasing, documented), while the hemicube on slivers or on
/// faces lying on others is off by 2e-2 to 0.36 (the heat sink, the atrium's plaques).
constexpr double kNonReciprocityWarning = 5e-3;
/// Warns (one line) when F's non-reciprocity part of the energy balance exceeds
/// kNonReciprocityWarning of the emitted power in some channel, naming the estimator and the
/// remedy.
void warn_about_non_reciprocity(const RadiositySolution& solution, const FormFactorOptions& ff);

/// The per-emitter bases of a solved `r` over F (r.bases, r.bases_seconds; relight.hpp), with
/// the solver options B was solved with.
void solve_bases(const LoadedScene& scene, const FormFactors& F, const SolveOptions& solver,
                 const RunArgs& run, RadiosityResult& r);

/// Computes F (or loads --ff) and solves for B (and with `bases` the per-emitter bases); logs
/// one line per stage on stderr.
RadiosityResult compute_radiosity(const LoadedScene& scene, const FormFactorArgs& ff,
                                  const SolveOptions& solver, const RunArgs& run,
                                  bool bases = false);

/// The per-vertex field of B and its per-surface power report.
struct ShadedField {
  VertexField field;
  std::vector<SurfacePower> power;
  std::string interpolation;  ///< the --vertex-interp used (auto resolved)
  double seconds = 0.0;
};
/// --vertex-interp with auto resolved: exact-direct on a --discontinuity mesh when
/// `indirect` is given and no surface is specular, else conservative. Throws UsageError for
/// an explicit exact-direct on a scene with specular surfaces.
std::string resolve_vertex_interp(const ShadeArgs& args, const LoadedScene& scene,
                                  const Eigen::MatrixX3d* indirect);
/// Interpolates B to the shading vertices with --vertex-interp. `indirect` (I = F (B - E),
/// or null when B came without F) is needed for exact-direct, which auto picks on a
/// --discontinuity mesh when it is given.
ShadedField shade_vertices(const LoadedScene& scene, const Eigen::MatrixX3d& B,
                           const Eigen::MatrixX3d* indirect, const ShadeArgs& args, int threads);

/// Why this scene's direct light cannot be drawn per pixel, empty when it can: F carries
/// light through mirrors and glass that the shadow rays do not, --sky/--sun light is not in
/// the indirect part, or too many emitting faces (PixelDirectLight::kMaxPieces).
std::string pixel_direct_obstacle(const LoadedScene& scene);
/// Refuses a --direct-rays N (N > 0) given on a scene where it cannot apply, before any work
/// (UsageError naming the obstacle).
void check_pixel_direct(const ShadeArgs& args, const LoadedScene& scene);
/// The vertex field that the direct light per pixel is drawn over: E + rho I per patch (I =
/// F (B - E), the indirect irradiance), interpolated with `interpolation`.
VertexField emitted_and_indirect_field(const PatchMesh& mesh, const Eigen::MatrixX3d& indirect,
                                       VertexInterpolation interpolation);

/// Renders the scene through `camera` (with the run's shared BVH, scene_bvh); raytraced
/// paths follow at most `specular_depth` specular bounces (--specular-depth). Camera rays
/// pass through `medium` when given (render.hpp's MediumView). With `indirect` (I = F (B -
/// E), B solved over F), Gouraud shading draws the emitters' direct light per pixel (shadow
/// rays, --direct-rays) over the vertex field of E + rho I, where pixel_direct_obstacle is
/// empty and `field` is not an exact-direct field (unless --direct-rays is given);
/// stats->direct_rays says whether it did.
Image render_scene(const LoadedScene& scene, const Eigen::MatrixX3d& B, const VertexField& field,
                   const Camera& camera, const ShadeArgs& args, int specular_depth,
                   const RunArgs& run, RenderStats* stats, const MediumView* medium = nullptr,
                   const Eigen::MatrixX3d* indirect = nullptr,
                   const std::string& interpolation = "conservative");

/// The exposure (EV) to use: --exposure, or automatic from the image (from the pixels that
/// hit the scene alone when `sky`: a sky behind it shows but does not set the exposure).
double choose_exposure(const ShadeArgs& args, const Image& image, bool sky = false);

/// Where to write what (empty = skip).
struct OutputPaths {
  std::string image_exr, png, vertex_exr, ply;
};

/// Writes the requested files atomically, side by side on up to `threads` threads (they
/// are independent), and returns the paths written, in a fixed order.
std::vector<std::string> write_outputs(const OutputPaths& paths, const PatchMesh& mesh,
                                       const ShadedField& shaded, const Image& image, double ev,
                                       const std::string& settings, int threads);

/// Largest relative power error over surfaces (after --vertex-interp) and before any rescale.
std::pair<double, double> worst_power_error(const std::vector<SurfacePower>& power);

}  // namespace lambert
