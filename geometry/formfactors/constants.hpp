#pragma once
// The geometric tolerances of the form-factor estimators, defined once (internal).

namespace lambert::ff {

/// Ray ends (and hemicube eyes) are lifted off their patches by this fraction of the
/// scene's bounding-box diagonal. Embree intersects in single precision (relative error
/// ~6e-8 of the coordinate magnitude); 1e-6 of the diagonal is > 10x that for any point
/// inside the box, yet far below any feature size a radiosity mesh resolves (the
/// form-factor bias it introduces is of the order of offset / patch size, < 1e-4 for 1e4
/// patches).
constexpr double kRayOffset = 1e-6;

/// Corners closer than this fraction of the diagonal to a patch's plane count as in the
/// plane (culling, hemicube edge-on tests): float-rounded coordinates of coplanar patches
/// differ by ~1e-16 relative, so 1e-12 is ~1e4 x double rounding and far below any
/// geometric feature.
constexpr double kPlaneEps = 1e-12;

}  // namespace lambert::ff
