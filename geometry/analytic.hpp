#pragma once
// Built-in analytic test scenes with closed-form view factors (Howell's catalog), used by
// the tests and by `lambert accuracy`. All lengths in metres (unitless), surfaces named
// "a" and "b" where a pair is involved.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "geometry/mesh/mesh.hpp"
#include "geometry/render/vertex_field.hpp"
#include "geometry/scene.hpp"

namespace lambert {

/// Two directly opposed parallel unit squares at distance `d`, facing each other.
Scene parallel_squares(double d = 1.0);
/// Exact F between directly opposed parallel rectangles a x b at distance c (Howell C-11).
double parallel_rectangles_factor(double a, double b, double c);

/// Exact A_1 F_12 (= G, units²) between axis-aligned parallel rectangles in the planes z = 0
/// ([x0, x1] x [y0, y1]) and z = h ([u0, u1] x [v0, v1]), in any lateral offset: the
/// four-fold corner sum of the contour integral (Ehlert & Smith 1993; Howell C-12 general).
double parallel_rectangles_G(double x0, double x1, double y0, double y1, double u0, double u1,
                             double v0, double v1, double h);

/// Two unit squares at right angles sharing an edge, both facing into the wedge.
Scene perpendicular_squares();
/// Exact F between perpendicular rectangles with a common edge of length l, widths w (from
/// the emitter, "a") and h (the receiver) (Howell C-14).
double perpendicular_rectangles_factor(double l, double w, double h);

/// The inside of the unit cube: six faces facing inwards, named +x, -x, +y, -y, +z, -z.
Scene unit_cube();
/// Exact F between opposite (or adjacent) faces of a cube: 0.199824896 (0.200043776).
constexpr double kCubeOpposite = 0.19982489569838732;
constexpr double kCubeAdjacent = 0.20004377607540316;

/// Two coaxial parallel disks of radii r1 ("a", emitter) and r2 ("b") at distance h,
/// approximated by regular polygons with `segments` sides (inscribed) of the same area.
Scene coaxial_disks(double r1, double r2, double h, int segments = 64);
/// Exact F from disk 1 to disk 2 (Howell C-41).
double coaxial_disks_factor(double r1, double r2, double h);

/// The partial-shadow scene: a grey floor [0, 4]² at z = 0 facing +z ("floor", rho 0.5), a
/// black square light [1.5, 2.5]² at z = 3 facing -z ("light", rho 0, E = 1) and a black
/// rectangular blocker [1.6, 2.6] x [1.3, 2.1] at z = 1.5 facing +z ("blocker", rho 0), off
/// centre so that umbra, penumbra and full light all reach the floor. Since nothing but the
/// floor reflects, the floor's radiosity is exactly B(x) = 0.5 x F_{dx->light, visible}
/// (shadowed_point_factor), its D1/D2 lines are the lines x = c or y = c of
/// partial_shadow_lines, and it has no D0 line.
Scene partial_shadow_scene();
/// The light, blocker and floor of partial_shadow_scene as polygons.
struct PartialShadowGeometry {
  std::vector<Eigen::Vector3d> light, blocker, floor;
};
PartialShadowGeometry partial_shadow_geometry();
/// A sharper soft shadow: the same floor, a 0.5 x 0.5 light [1.75, 2.25]² at z = 3 and a
/// 1 x 1 blocker [1.4, 2.4]² at z = 1 (off centre by 0.1): penumbrae 0.25 wide (light size x
/// h_b / (H - h_b)) around a 1.25 x 1.25 umbra, the rest of the floor smoothly lit.
PartialShadowGeometry square_shadow_geometry();
/// The scene of a floor (z = 0, faces +z, rho 0.5), a light (faces -z, rho 0, E = 1) and a
/// black blocker (faces +z): only the floor reflects and it cannot see itself, so its
/// radiosity is exactly 0.5 x shadowed_point_factor (partial_shadow_scene is
/// shadow_scene(partial_shadow_geometry())).
Scene shadow_scene(const PartialShadowGeometry& g);
/// The positions c of its D1/D2 lines on the floor, in x (first) and y (second): every
/// light corner coordinate projected through every blocker edge coordinate,
/// s + (b - s) H / (H - h_b), that falls inside the floor.
std::pair<std::vector<double>, std::vector<double>> partial_shadow_lines();

/// The exact floor radiosity of partial_shadow_scene at a floor point x (z = 0):
/// 0.5 x shadowed_point_factor(x, +z, light, {blocker}).
double partial_shadow_floor_radiosity(const Eigen::Vector3d& x);
/// The same on shadow_scene(g): 0.5 x shadowed_point_factor(x, +z, g.light, {g.blocker}).
double shadow_floor_radiosity(const PartialShadowGeometry& g, const Eigen::Vector3d& x);
/// The exact occluded surface factor F_{floor->light} of partial_shadow_scene: the floor
/// cut along every line of partial_shadow_lines into rectangles inside which the visible
/// part of the light changes smoothly, each integrated by a tensor Gauss-Legendre rule of
/// `order` points per direction (the integrand is analytic in each cell, so the rule
/// converges exponentially: orders 12 and 20 agree to rounding, about 1e-16).
double partial_shadow_floor_light_factor(int order = 16);

/// Errors of a floor radiosity on partial_shadow_scene against the exact field.
struct PartialShadowErrors {
  double l1 = 0.0;    ///< area-mean |B_i - B(x)| of the patch constants (midpoint rule, 16 per triangle)
  double line = 0.0;  ///< largest |f(x) - B(x)| of the interpolated vertex field f on y = 1.75
  double field_l1 = 0.0;  ///< area-mean |f(x) - B(x)| of the interpolated field (same rule as l1)
};
/// `B` (N x 3, its channel mean is used) and its vertex field on a mesh of
/// partial_shadow_scene: both errors. The line crosses the umbra and both penumbrae in x,
/// 0.05 from the umbra's edge y = 1.7 (400 points on x in [0.2, 3.8]).
PartialShadowErrors partial_shadow_errors(const PatchMesh& mesh, const Eigen::MatrixX3d& B,
                                          const VertexField& field);
/// The same on shadow_scene(g), the line at y = line_y.
PartialShadowErrors shadow_errors(const PartialShadowGeometry& g, const PatchMesh& mesh,
                                  const Eigen::MatrixX3d& B, const VertexField& field,
                                  double line_y);

/// An analytic case: its scene and the exact factor from surface "a" to surface "b".
struct AnalyticCase {
  std::string name;
  Scene scene;
  double exact_ab = 0.0;
};
/// The built-in analytic cases (parallel squares, perpendicular squares, coaxial disks).
std::vector<AnalyticCase> analytic_cases();

}  // namespace lambert
