#include "geometry/vertex_field.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace lambert {
namespace {

// Gauss-Legendre 2-point nodes on [0, 1]: 1/2 ± 1/(2√3), weights 1/2 each.
constexpr double kGauss0 = 0.21132486540518711775;
constexpr double kGauss1 = 0.78867513459481288225;

// Bilinear map of a quad and its partial derivatives at (u, v); corners 0..3 at
// (0,0), (1,0), (1,1), (0,1).
struct Bilinear {
  Eigen::Vector3d a, b, c, d;
  Eigen::Vector3d at(double u, double v) const {
    return (1 - u) * (1 - v) * a + u * (1 - v) * b + u * v * c + (1 - u) * v * d;
  }
  Eigen::Vector3d du(double v) const { return (1 - v) * (b - a) + v * (c - d); }
  Eigen::Vector3d dv(double u) const { return (1 - u) * (d - a) + u * (c - b); }
};

Bilinear quad_of(const PatchMesh& mesh, const Patch& p) {
  return {mesh.vertices[p.vertices[0]], mesh.vertices[p.vertices[1]], mesh.vertices[p.vertices[2]],
          mesh.vertices[p.vertices[3]]};
}

double relative(const Eigen::Vector3d& value, const Eigen::Vector3d& reference) {
  double worst = 0.0;
  for (int c = 0; c < 3; ++c)
    if (reference[c] != 0.0)
      worst = std::max(worst, std::abs(value[c] - reference[c]) / std::abs(reference[c]));
  return worst;
}

}  // namespace

VertexInterpolation parse_vertex_interpolation(const std::string& name) {
  if (name == "area") return VertexInterpolation::AreaWeighted;
  if (name == "conservative") return VertexInterpolation::Conservative;
  throw UsageError("unknown vertex interpolation '" + name + "' (use area or conservative)");
}

const char* to_string(VertexInterpolation mode) {
  return mode == VertexInterpolation::AreaWeighted ? "area" : "conservative";
}

double SurfacePower::relative_error() const { return relative(field_power, patch_power); }

double SurfacePower::area_weighted_relative_error() const {
  return relative(area_weighted_power, patch_power);
}

VertexField build_shading_vertices(const PatchMesh& mesh) {
  const auto nv = mesh.vertices.size();
  // Patches around each mesh vertex (with the corner slot), in patch order: deterministic.
  std::vector<std::vector<std::pair<std::int32_t, int>>> around(nv);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    for (int k = 0; k < p.vertex_count; ++k) around[p.vertices[k]].push_back({i, k});
  }
  const double cos_crease = std::cos(kCreaseAngleDegrees * M_PI / 180.0);
  VertexField f;
  f.patch_corners.assign(mesh.patches.size(), {-1, -1, -1, -1});
  for (size_t v = 0; v < nv; ++v) {
    // Greedy smoothing groups: a patch joins the first group whose mean normal is within
    // the crease angle of its own, else starts a new one.
    std::vector<Eigen::Vector3d> group_normal;  // area-weighted sum of normals
    std::vector<std::int32_t> group_id;
    for (const auto& [i, k] : around[v]) {
      const Patch& p = mesh.patches[i];
      size_t g = 0;
      for (; g < group_normal.size(); ++g)
        if (group_normal[g].normalized().dot(p.normal) >= cos_crease) break;
      if (g == group_normal.size()) {
        group_normal.push_back(Eigen::Vector3d::Zero());
        group_id.push_back(f.size());
        f.positions.push_back(mesh.vertices[v]);
        f.normals.push_back(Eigen::Vector3d::Zero());
        f.surface.push_back(mesh.vertex_surface[v]);
        f.mesh_vertex.push_back(static_cast<std::int32_t>(v));
      }
      group_normal[g] += p.area * p.normal;
      f.patch_corners[i][k] = group_id[g];
    }
    for (size_t g = 0; g < group_normal.size(); ++g)
      f.normals[group_id[g]] = group_normal[g].normalized();
  }
  f.values = Eigen::MatrixX3d::Zero(f.size(), 3);
  return f;
}

Eigen::Vector3d integrate_patch(const PatchMesh& mesh, const VertexField& field, std::int32_t i) {
  const Patch& p = mesh.patches[i];
  const auto& c = field.patch_corners[i];
  if (p.vertex_count == 3) {
    return p.area / 3.0 *
           (field.values.row(c[0]) + field.values.row(c[1]) + field.values.row(c[2])).transpose();
  }
  // ∫ f dA = ∫∫ f(u,v) J(u,v) du dv with J = n · (x_u × x_v), linear for a planar quad.
  const Bilinear q = quad_of(mesh, p);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (double u : {kGauss0, kGauss1}) {
    for (double v : {kGauss0, kGauss1}) {
      const double jac = p.normal.dot(q.du(v).cross(q.dv(u)));
      const Eigen::Vector3d fv =
          ((1 - u) * (1 - v) * field.values.row(c[0]) + u * (1 - v) * field.values.row(c[1]) +
           u * v * field.values.row(c[2]) + (1 - u) * v * field.values.row(c[3]))
              .transpose();
      sum += 0.25 * jac * fv;
    }
  }
  return sum;
}

std::vector<SurfacePower> surface_power(const PatchMesh& mesh, const Eigen::MatrixX3d& patch_values,
                                        const VertexField& field) {
  std::vector<SurfacePower> out(mesh.surface_names.size());
  for (size_t s = 0; s < out.size(); ++s) out[s].name = mesh.surface_names[s];
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    LAMBERT_CHECK(p.surface >= 0 && static_cast<size_t>(p.surface) < out.size(),
                  "patch surface out of range");
    SurfacePower& s = out[p.surface];
    s.area += p.area;
    s.patch_power += p.area * patch_values.row(i).transpose();
    s.field_power += integrate_patch(mesh, field, i);
  }
  for (auto& s : out) s.area_weighted_power = s.field_power;
  return out;
}

VertexField interpolate_to_vertices(const PatchMesh& mesh, const Eigen::MatrixX3d& patch_values,
                                    VertexInterpolation mode, std::vector<SurfacePower>* power) {
  LAMBERT_CHECK(patch_values.rows() == mesh.size(), "patch field size does not match the mesh");
  VertexField f = build_shading_vertices(mesh);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(f.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    for (int k = 0; k < p.vertex_count; ++k) {
      f.values.row(f.patch_corners[i][k]) += p.area * patch_values.row(i);
      weight[f.patch_corners[i][k]] += p.area;
    }
  }
  for (std::int32_t k = 0; k < f.size(); ++k)
    if (weight[k] > 0) f.values.row(k) /= weight[k];

  std::vector<SurfacePower> pw = surface_power(mesh, patch_values, f);
  if (mode == VertexInterpolation::Conservative) {
    for (auto& s : pw) {
      for (int c = 0; c < 3; ++c) {
        // Values are >= 0 for a radiosity field; rescale only where both powers are positive
        // (a zero field stays zero, a signed test field is left as interpolated).
        if (s.patch_power[c] > 0 && s.field_power[c] > 0)
          s.scale[c] = s.patch_power[c] / s.field_power[c];
      }
    }
    for (std::int32_t k = 0; k < f.size(); ++k)
      f.values.row(k).array() *= pw[f.surface[k]].scale.transpose().array();
    // Recompute the integral of the final field (what the report states).
    const std::vector<SurfacePower> after = surface_power(mesh, patch_values, f);
    for (size_t s = 0; s < pw.size(); ++s) pw[s].field_power = after[s].field_power;
  }
  if (power) *power = std::move(pw);
  return f;
}

std::array<double, 4> patch_weights(const PatchMesh& mesh, std::int32_t i,
                                    const Eigen::Vector3d& x) {
  const Patch& p = mesh.patches[i];
  if (p.vertex_count == 3) {
    // Barycentric coordinates by least squares in the triangle's plane.
    const Eigen::Vector3d& a = mesh.vertices[p.vertices[0]];
    const Eigen::Vector3d e1 = mesh.vertices[p.vertices[1]] - a;
    const Eigen::Vector3d e2 = mesh.vertices[p.vertices[2]] - a;
    const Eigen::Vector3d d = x - a;
    const double d00 = e1.dot(e1), d01 = e1.dot(e2), d11 = e2.dot(e2);
    const double d20 = d.dot(e1), d21 = d.dot(e2);
    const double den = d00 * d11 - d01 * d01;
    double b = (d11 * d20 - d01 * d21) / den;
    double c = (d00 * d21 - d01 * d20) / den;
    double w0 = 1.0 - b - c;
    w0 = std::max(w0, 0.0);
    b = std::max(b, 0.0);
    c = std::max(c, 0.0);
    const double s = w0 + b + c;
    return {w0 / s, b / s, c / s, 0.0};
  }
  // Invert the bilinear map by Gauss-Newton from the centre; a planar convex quad has a
  // unique preimage and the iteration converges quadratically (a few steps to 1e-12).
  const Bilinear q = quad_of(mesh, p);
  double u = 0.5, v = 0.5;
  for (int it = 0; it < 16; ++it) {
    const Eigen::Vector3d r = x - q.at(u, v);
    const Eigen::Vector3d xu = q.du(v), xv = q.dv(u);
    const double a00 = xu.dot(xu), a01 = xu.dot(xv), a11 = xv.dot(xv);
    const double r0 = xu.dot(r), r1 = xv.dot(r);
    const double den = a00 * a11 - a01 * a01;
    if (!(den > 0)) break;
    const double du = (a11 * r0 - a01 * r1) / den;
    const double dv = (a00 * r1 - a01 * r0) / den;
    u += du;
    v += dv;
    if (std::abs(du) + std::abs(dv) < 1e-13) break;
  }
  u = std::clamp(u, 0.0, 1.0);
  v = std::clamp(v, 0.0, 1.0);
  return {(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v};
}

}  // namespace lambert
