#include "geometry/analytic.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "geometry/formfactors/kernels.hpp"
#include "geometry/visibility/shadow.hpp"

namespace lambert {
namespace {
Material grey() { return {"grey", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()}; }
Material lamp() { return {"lamp", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Ones()}; }
}  // namespace

PartialShadowGeometry partial_shadow_geometry() {
  PartialShadowGeometry g;
  g.floor = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}};            // faces +z
  g.light = {{1.5, 1.5, 3}, {1.5, 2.5, 3}, {2.5, 2.5, 3}, {2.5, 1.5, 3}};  // faces -z
  g.blocker = {{1.6, 1.3, 1.5}, {2.6, 1.3, 1.5}, {2.6, 2.1, 1.5}, {1.6, 2.1, 1.5}};  // +z
  return g;
}

PartialShadowGeometry square_shadow_geometry() {
  PartialShadowGeometry g;
  g.floor = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}};                          // faces +z
  g.light = {{1.75, 1.75, 3}, {1.75, 2.25, 3}, {2.25, 2.25, 3}, {2.25, 1.75, 3}};  // faces -z
  g.blocker = {{1.4, 1.4, 1}, {2.4, 1.4, 1}, {2.4, 2.4, 1}, {1.4, 2.4, 1}};        // faces +z
  return g;
}

Scene partial_shadow_scene() { return shadow_scene(partial_shadow_geometry()); }

Scene shadow_scene(const PartialShadowGeometry& g) {
  Scene s;
  add_polygon(s, "floor", grey(), g.floor);
  add_polygon(s, "light", {"light", Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()}, g.light);
  add_polygon(s, "blocker", {"black", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}, g.blocker);
  s.camera = framing_camera({0, 0, 0}, {4, 4, 3});
  return s;
}

std::pair<std::vector<double>, std::vector<double>> partial_shadow_lines() {
  const double H = 3.0, hb = 1.5;
  std::pair<std::vector<double>, std::vector<double>> lines;
  auto project = [&](std::initializer_list<double> light, std::initializer_list<double> blocker,
                     std::vector<double>& out) {
    for (double s : light)
      for (double b : blocker) {
        const double c = s + (b - s) * H / (H - hb);
        if (c > 0 && c < 4) out.push_back(c);
      }
  };
  project({1.5, 2.5}, {1.6, 2.6}, lines.first);
  project({1.5, 2.5}, {1.3, 2.1}, lines.second);
  return lines;
}

double partial_shadow_floor_radiosity(const Eigen::Vector3d& x) {
  static const PartialShadowGeometry g = partial_shadow_geometry();
  return shadow_floor_radiosity(g, x);
}

double shadow_floor_radiosity(const PartialShadowGeometry& g, const Eigen::Vector3d& x) {
  return 0.5 * shadowed_point_factor(x, Eigen::Vector3d::UnitZ(), g.light, {g.blocker});
}

double partial_shadow_floor_light_factor(int order) {
  const PartialShadowGeometry g = partial_shadow_geometry();
  auto [xs, ys] = partial_shadow_lines();
  for (auto* cuts : {&xs, &ys}) {
    cuts->push_back(0.0);
    cuts->push_back(4.0);
    std::sort(cuts->begin(), cuts->end());
  }
  const ff::GaussRule rule = ff::gauss_legendre(order);
  double sum = 0.0;
  for (size_t a = 0; a + 1 < xs.size(); ++a)
    for (size_t b = 0; b + 1 < ys.size(); ++b) {
      const double wx = xs[a + 1] - xs[a], wy = ys[b + 1] - ys[b];
      for (int i = 0; i < order; ++i)
        for (int j = 0; j < order; ++j) {
          const Eigen::Vector3d x(xs[a] + wx * rule.x[i], ys[b] + wy * rule.x[j], 0.0);
          sum += wx * wy * rule.w[i] * rule.w[j] *
                 shadowed_point_factor(x, Eigen::Vector3d::UnitZ(), g.light, {g.blocker});
        }
    }
  return sum / 16.0;  // the floor's area
}

namespace {

bool inside_patch(const PatchMesh& m, const Patch& p, const Eigen::Vector3d& x) {
  for (int c = 0; c < p.vertex_count; ++c) {
    const Eigen::Vector3d a = m.vertices[p.vertices[c]], b = m.vertices[p.vertices[(c + 1) % p.vertex_count]];
    if ((b - a).cross(x - a).z() < -1e-12) return false;
  }
  return true;
}

}  // namespace

PartialShadowErrors partial_shadow_errors(const PatchMesh& m, const Eigen::MatrixX3d& B,
                                          const VertexField& field) {
  static const PartialShadowGeometry g = partial_shadow_geometry();
  return shadow_errors(g, m, B, field, 1.75);
}

PartialShadowErrors shadow_errors(const PartialShadowGeometry& g, const PatchMesh& m,
                                  const Eigen::MatrixX3d& B, const VertexField& field,
                                  double line_y) {
  const auto exact = [&](const Eigen::Vector3d& x) { return shadow_floor_radiosity(g, x); };
  PartialShadowErrors e;
  double area = 0;
  for (std::int32_t i = 0; i < m.size(); ++i) {
    const Patch& p = m.patches[i];
    if (m.surface_names[p.surface] != "floor") continue;
    const double bi = B.row(i).mean();
    for (int t = 1; t + 1 < p.vertex_count; ++t) {
      const Eigen::Vector3d a = m.vertices[p.vertices[0]], b = m.vertices[p.vertices[t]],
                            c = m.vertices[p.vertices[t + 1]];
      const double A = 0.5 * (b - a).cross(c - a).norm();
      // Midpoint rule on the 16 similar sub-triangles (centroids of the 10 upright and 6
      // inverted ones): its own error is O(h²/16 B''), below the O(h B') measured.
      const int n = 4;
      double err = 0, field_err = 0;
      auto add = [&](const Eigen::Vector3d& x) {
        const double bx = exact(x);
        err += std::abs(bi - bx);
        const auto w = patch_weights(m, i, x);
        double f = 0;
        for (int k = 0; k < p.vertex_count; ++k)
          f += w[k] * field.values.row(field.patch_corners[i][k]).mean();
        field_err += std::abs(f - bx);
      };
      for (int u = 0; u < n; ++u)
        for (int v = 0; u + v < n; ++v) {
          const Eigen::Vector3d o = a + (b - a) * u / n + (c - a) * v / n;
          add(o + ((b - a) + (c - a)) / (3.0 * n));
          if (u + v < n - 1) add(o + (2.0 * (b - a) + 2.0 * (c - a)) / (3.0 * n));
        }
      e.l1 += A * err / (n * n);
      e.field_l1 += A * field_err / (n * n);
      area += A;
    }
  }
  e.l1 /= area;
  e.field_l1 /= area;
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector3d x(0.2 + 3.6 * (k + 0.5) / 400, line_y, 0);
    for (std::int32_t i = 0; i < m.size(); ++i) {
      const Patch& p = m.patches[i];
      if (m.surface_names[p.surface] != "floor" || !inside_patch(m, p, x)) continue;
      const auto w = patch_weights(m, i, x);
      double value = 0;
      for (int c = 0; c < p.vertex_count; ++c) value += w[c] * field.values.row(field.patch_corners[i][c]).mean();
      e.line = std::max(e.line, std::abs(value - exact(x)));
      break;
    }
  }
  return e;
}

Scene parallel_squares(double d) {
  Scene s;
  add_polygon(s, "a", lamp(), {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});  // faces +z
  add_polygon(s, "b", grey(), {{0, 0, d}, {0, 1, d}, {1, 1, d}, {1, 0, d}});  // faces -z
  s.camera = framing_camera({0, 0, 0}, {1, 1, d});
  return s;
}

double parallel_rectangles_factor(double a, double b, double c) {
  const double X = a / c, Y = b / c;
  const double X2 = 1 + X * X, Y2 = 1 + Y * Y;
  return 2.0 / (M_PI * X * Y) *
         (std::log(std::sqrt(X2 * Y2 / (X2 + Y2 - 1))) + X * std::sqrt(Y2) * std::atan(X / std::sqrt(Y2)) +
          Y * std::sqrt(X2) * std::atan(Y / std::sqrt(X2)) - X * std::atan(X) - Y * std::atan(Y));
}

double parallel_rectangles_G(double x0, double x1, double y0, double y1, double u0, double u1,
                             double v0, double v1, double h) {
  // G = (1/2π) Σ (-1)^(i+j+k+l) g(x_i - u_k, y_j - v_l) with
  // g(p, q) = q sqrt(p² + h²) atan(q / sqrt(p² + h²)) + p sqrt(q² + h²) atan(p / sqrt(q² + h²))
  //           - (h² / 2) ln(p² + q² + h²).
  auto g = [h](double p, double q) {
    const double ph = std::sqrt(p * p + h * h), qh = std::sqrt(q * q + h * h);
    return q * ph * std::atan(q / ph) + p * qh * std::atan(p / qh) -
           0.5 * h * h * std::log(p * p + q * q + h * h);
  };
  const double xs[2] = {x0, x1}, ys[2] = {y0, y1}, us[2] = {u0, u1}, vs[2] = {v0, v1};
  double sum = 0.0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k)
        for (int l = 0; l < 2; ++l)
          sum += ((i + j + k + l) % 2 ? -1.0 : 1.0) * g(xs[i] - us[k], ys[j] - vs[l]);
  return sum / (2.0 * M_PI);
}

Scene perpendicular_squares() {
  Scene s;
  add_polygon(s, "a", lamp(), {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});  // z=0, faces +z
  add_polygon(s, "b", grey(), {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}});  // x=0, faces +x
  s.camera = framing_camera({0, 0, 0}, {1, 1, 1});
  return s;
}

double perpendicular_rectangles_factor(double l, double w, double h) {
  const double H = h / l, W = w / l;
  const double H2 = H * H, W2 = W * W, HW = H2 + W2;
  const double t1 = W * std::atan(1 / W) + H * std::atan(1 / H) - std::sqrt(HW) * std::atan(1 / std::sqrt(HW));
  const double a = (1 + W2) * (1 + H2) / (1 + HW);
  const double b = W2 * (1 + HW) / ((1 + W2) * HW);
  const double c = H2 * (1 + HW) / ((1 + H2) * HW);
  const double t2 = 0.25 * std::log(a * std::pow(b, W2) * std::pow(c, H2));
  return (t1 + t2) / (M_PI * W);
}

Scene unit_cube() {
  Scene s;
  // Each face wound counter-clockwise about its inward normal.
  add_polygon(s, "-x", grey(), {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}});  // normal +x
  add_polygon(s, "+x", grey(), {{1, 0, 0}, {1, 0, 1}, {1, 1, 1}, {1, 1, 0}});  // normal -x
  add_polygon(s, "-y", grey(), {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}});  // normal +y
  add_polygon(s, "+y", lamp(), {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}});  // normal -y
  add_polygon(s, "-z", grey(), {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});  // normal +z
  add_polygon(s, "+z", grey(), {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}});  // normal -z
  s.camera = framing_camera({0, 0, 0}, {1, 1, 1});
  return s;
}

Scene coaxial_disks(double r1, double r2, double h, int segments) {
  Scene s;
  // Regular polygons with the disk's area: circumradius R with (n/2) R² sin(2π/n) = π r².
  auto ring = [&](double r, double z, bool up) {
    const double R = r * std::sqrt(2 * M_PI / (segments * std::sin(2 * M_PI / segments)));
    std::vector<Eigen::Vector3d> p;
    for (int k = 0; k < segments; ++k) {
      const double t = 2 * M_PI * (up ? k : segments - k) / segments;
      p.emplace_back(R * std::cos(t), R * std::sin(t), z);
    }
    return p;
  };
  add_polygon(s, "a", lamp(), ring(r1, 0, true));   // faces +z
  add_polygon(s, "b", grey(), ring(r2, h, false));  // faces -z
  const double r = std::max(r1, r2);
  s.camera = framing_camera({-r, -r, 0}, {r, r, h});
  return s;
}

double coaxial_disks_factor(double r1, double r2, double h) {
  const double R1 = r1 / h, R2 = r2 / h;
  const double X = 1 + (1 + R2 * R2) / (R1 * R1);
  return 0.5 * (X - std::sqrt(X * X - 4 * (R2 / R1) * (R2 / R1)));
}

std::vector<AnalyticCase> analytic_cases() {
  return {
      {"parallel_squares", parallel_squares(1.0), parallel_rectangles_factor(1, 1, 1)},
      {"perpendicular_squares", perpendicular_squares(), perpendicular_rectangles_factor(1, 1, 1)},
      {"coaxial_disks", coaxial_disks(0.5, 0.5, 1.0, 64), coaxial_disks_factor(0.5, 0.5, 1.0)},
  };
}

}  // namespace lambert
