#pragma once
// The .glb and the viewer page of a solution (docs/viewer.md): the shading-vertex mesh with
// the solution and its per-emitter bases (pipeline/relight.hpp) as vertex colours.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "geometry/render/camera.hpp"
#include "io/glb.hpp"
#include "pipeline/job.hpp"
#include "pipeline/relight.hpp"
#include "pipeline/render_stages.hpp"

namespace lambert {

/// What the glb describes besides the mesh.
struct ViewerInputs {
  const PatchMesh& mesh;
  const Daylight& daylight;                ///< its sky is drawn behind the scene
  std::string scene;                       ///< the scene's file (asset.extras)
  const Eigen::MatrixX3d& B;               ///< the solution (N x 3)
  const ShadedField& shaded;               ///< its vertex field (as in the vertex EXR)
  const std::vector<EmitterBasis>& bases;  ///< empty: no relighting
  std::string no_relighting;               ///< why there are no bases (when empty)
  const Camera& camera;
  double ev = 0.0;       ///< the tone-mapping exposure of the PNG
  std::string settings;  ///< the settings line
};

/// The .glb content: the shading-vertex mesh with COLOR_0 = the solution and COLOR_k = basis k
/// (radiosity, W/m² in the scene's units), the patch edges, the camera, and in asset.extras
/// ("lambert") the units, the exposure, the emitters and the measured linearity error
/// (`linearity_error`, also returned). exact-direct vertex values are not linear in a way the
/// bases can follow; the glb then carries conservative ones.
GlbContent viewer_glb(const ViewerInputs& in, double* linearity_error = nullptr);

/// A heat result for the viewer: the patches' temperature T (K, NaN where undefined), net
/// flux q and radiosity J (W/m²).
struct HeatViewerInputs {
  const PatchMesh& mesh;
  const Eigen::VectorXd &T, &q, &J;
  const Camera& camera;
  std::string scene;     ///< the scene's file (asset.extras)
  std::string settings;  ///< the settings line
};

/// The .glb of a heat result: the shading-vertex mesh with _TEMPERATURE (K) and _HEAT_FLUX
/// (W/m², net, leaving) per vertex, area-weighted like heat's vertex EXR (an undefined
/// temperature as 0 K, counted in asset.extras), COLOR_0 the thermal radiosity J, the patch
/// edges and the camera; the viewer opens it on the temperature.
GlbContent heat_viewer_glb(const HeatViewerInputs& in);

/// Writes `glb` to `glb_path` and the viewer page embedding it to `page_path` (either may be
/// empty), atomically. Returns the paths written.
std::vector<std::string> write_viewer(const GlbContent& glb, const std::string& glb_path,
                                      const std::string& page_path, const std::string& title);

}  // namespace lambert
