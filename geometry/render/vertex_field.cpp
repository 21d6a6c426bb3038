#include "geometry/render/vertex_field.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

#include "core/error.hpp"
#include "core/sampling.hpp"
#include "geometry/formfactors/kernels.hpp"
#include "geometry/visibility/direct_light.hpp"

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

// Unit normals with a smaller dot product than this are on either side of a crease.
double cos_crease() { return std::cos(kCreaseAngleDegrees * M_PI / 180.0); }

// Shading vertices hashed by (surface, exact position), open addressing with linear probing
// in a table at most half full: the ones at a point are found in O(1) expected. -0.0 hashes
// as +0.0 (x + 0.0), since == (the exact-position test) makes them equal.
class PositionIndex {
 public:
  explicit PositionIndex(const VertexField& f) : f_(f) {
    size_t size = 16;
    while (size < 2 * f.positions.size()) size *= 2;
    mask_ = size - 1;
    slots_.assign(size, -1);
    for (std::int32_t v = 0; v < f.size(); ++v) {
      size_t s = home(f.surface[v], f.positions[v]);
      while (slots_[s] >= 0) s = (s + 1) & mask_;
      slots_[s] = v;
    }
  }

  // Calls visit(v) for each shading vertex v of `surface` at exactly x; returns how many.
  template <class Visit>
  int for_each_at(std::int32_t surface, const Eigen::Vector3d& x, Visit&& visit) const {
    int count = 0;
    for (size_t s = home(surface, x); slots_[s] >= 0; s = (s + 1) & mask_) {
      const std::int32_t v = slots_[s];
      if (f_.surface[v] != surface || f_.positions[v] != x) continue;
      visit(v);
      ++count;
    }
    return count;
  }

 private:
  size_t home(std::int32_t surface, const Eigen::Vector3d& x) const {
    std::uint64_t h = mix64(static_cast<std::uint64_t>(surface));
    for (int c = 0; c < 3; ++c) {
      const double coordinate = x[c] + 0.0;
      std::uint64_t bits;
      std::memcpy(&bits, &coordinate, sizeof bits);
      h = mix64(h ^ bits);
    }
    return static_cast<size_t>(h) & mask_;
  }

  const VertexField& f_;
  size_t mask_ = 0;
  std::vector<std::int32_t> slots_;  // shading vertex, or -1 for an empty slot
};

// The part [t0, t1] of a patch edge still to search, with the positions of its ends.
struct EdgeSegment {
  Eigen::Vector3d x0, x1;
  double t0 = 0.0, t1 = 1.0;
};

// The search for hanging vertices along patch edges, in discovery order (patch, edge, then
// depth-first halves); a shading vertex found twice keeps its first anchor.
class HangingSearch {
 public:
  HangingSearch(const PatchMesh& mesh, const VertexField& f)
      : mesh_(mesh), f_(f), index_(f), anchor_of_(f.size(), -1) {}

  // Appends the shading vertices hanging on edge (corner k, corner k + 1) of patch i and
  // compatible with it: midpoints looked up while found, halving the segment.
  void search_edge(std::int32_t i, int k) {
    const Patch& p = mesh_.patches[i];
    const int k1 = (k + 1) % p.vertex_count;
    todo_.push_back({mesh_.vertices[p.vertices[k]], mesh_.vertices[p.vertices[k1]], 0.0, 1.0});
    while (!todo_.empty()) {
      const EdgeSegment s = todo_.back();
      todo_.pop_back();
      const Eigen::Vector3d m = 0.5 * (s.x0 + s.x1);
      if (m == s.x0 || m == s.x1) continue;  // the segment is down to rounding
      const double t = 0.5 * (s.t0 + s.t1);
      const int at_m = index_.for_each_at(p.surface, m, [&](std::int32_t v) {
        if (anchor_of_[v] >= 0 || f_.normals[v].dot(p.normal) < cos_max_) return;
        anchor_of_[v] = static_cast<std::int32_t>(found_.size());
        found_.push_back({v, f_.patch_corners[i][k], f_.patch_corners[i][k1], t, i});
      });
      if (at_m == 0) continue;  // no vertex at m: none finer
      todo_.push_back({m, s.x1, t, s.t1});
      todo_.push_back({s.x0, m, s.t0, t});
    }
  }

  // The anchors found so far.
  const std::vector<HangingVertex>& found() const { return found_; }

 private:
  const PatchMesh& mesh_;
  const VertexField& f_;
  const PositionIndex index_;
  const double cos_max_ = cos_crease();
  std::vector<std::int32_t> anchor_of_;  // per shading vertex: index into found_, or -1
  std::vector<HangingVertex> found_;
  std::vector<EdgeSegment> todo_;  // depth-first stack of segments to search
};

// Orders `found` so that every anchor follows the anchors of its ends (Kahn's algorithm).
// When only cycles remain, the first unfinished anchor is dropped (its vertex keeps its
// value) and the sort goes on: n steps, each finishing one anchor.
std::vector<HangingVertex> resolution_order(const std::vector<HangingVertex>& found,
                                            std::int32_t vertices) {
  const auto n = static_cast<std::int32_t>(found.size());
  std::vector<std::int32_t> anchor_of(vertices, -1);
  for (std::int32_t j = 0; j < n; ++j) anchor_of[found[j].vertex] = j;
  // Dependents of each anchor (CSR): j depends on the anchors of its ends a and b.
  std::vector<std::int32_t> start(n + 1, 0), pending(n, 0);
  for (std::int32_t j = 0; j < n; ++j) {
    for (std::int32_t end : {found[j].a, found[j].b}) {
      if (anchor_of[end] < 0) continue;
      ++start[anchor_of[end] + 1];
      ++pending[j];
    }
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::int32_t> dependents(start[n]), fill(start.begin(), start.end() - 1);
  for (std::int32_t j = 0; j < n; ++j)
    for (std::int32_t end : {found[j].a, found[j].b})
      if (anchor_of[end] >= 0) dependents[fill[anchor_of[end]]++] = j;

  std::vector<char> done(n, 0);
  std::vector<std::int32_t> ready;  // FIFO: ready[head..] are waiting
  for (std::int32_t j = 0; j < n; ++j)
    if (pending[j] == 0) ready.push_back(j);
  std::vector<HangingVertex> order;
  order.reserve(n);
  size_t head = 0;
  std::int32_t unfinished = 0;
  for (std::int32_t step = 0; step < n; ++step) {
    std::int32_t j;
    if (head < ready.size()) {
      j = ready[head++];
      order.push_back(found[j]);
    } else {
      while (done[unfinished]) ++unfinished;
      j = unfinished;  // on a cycle: dropped
    }
    done[j] = 1;
    for (std::int32_t d = start[j]; d < start[j + 1]; ++d)
      if (--pending[dependents[d]] == 0 && !done[dependents[d]]) ready.push_back(dependents[d]);
  }
  return order;
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
  if (name == "linear") return VertexInterpolation::LinearFit;
  throw UsageError("unknown vertex interpolation '" + name +
                   "' (use area, conservative or linear)");
}

const char* to_string(VertexInterpolation mode) {
  return mode == VertexInterpolation::AreaWeighted ? "area"
         : mode == VertexInterpolation::LinearFit  ? "linear"
                                                   : "conservative";
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
  const double cos_max = cos_crease();
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
        if (group_normal[g].normalized().dot(p.normal) >= cos_max) break;
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

std::vector<HangingVertex> find_hanging_vertices(const PatchMesh& mesh, const VertexField& field) {
  LAMBERT_CHECK(field.patch_corners.size() == mesh.patches.size(),
                "vertex field does not match the mesh");
  HangingSearch search(mesh, field);
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    for (int k = 0; k < mesh.patches[i].vertex_count; ++k) search.search_edge(i, k);
  return resolution_order(search.found(), field.size());
}

void anchor_hanging_vertices(const std::vector<HangingVertex>& hanging, VertexField& field) {
  // v_a + t (v_b - v_a) rather than (1 - t) v_a + t v_b: exact when v_a = v_b (a constant).
  for (const HangingVertex& h : hanging)
    field.values.row(h.vertex) =
        field.values.row(h.a) + h.t * (field.values.row(h.b) - field.values.row(h.a));
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

namespace {

// linear_fit's conditioning bound: its centroids must spread at least 1/30 as much (in
// variance) across as along (about 1:5.5 in extent), else the fit's slope across is
// unresolved and extrapolating it would amplify the patch values' noise.
constexpr double kFitCondition = 1.0 / 30.0;

// The area-weighted mean of a per-patch field (N x 3) at every shading vertex of f.
Eigen::MatrixX3d area_weighted(const PatchMesh& mesh, const VertexField& f,
                               const Eigen::MatrixX3d& patch_values) {
  Eigen::MatrixX3d values = Eigen::MatrixX3d::Zero(f.size(), 3);
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(f.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    const Patch& p = mesh.patches[i];
    for (int k = 0; k < p.vertex_count; ++k) {
      values.row(f.patch_corners[i][k]) += p.area * patch_values.row(i);
      weight[f.patch_corners[i][k]] += p.area;
    }
  }
  for (std::int32_t k = 0; k < f.size(); ++k)
    if (weight[k] > 0) values.row(k) /= weight[k];
  return values;
}

// The value at every shading vertex k of the local linear fit of the patch values around
// it: weighted least squares b_i ≈ a + g · d_i over its patches i (weights A_i, d_i = c_i -
// x_k the centroid offsets in the plane of the vertex normal), v_k = a, clamped to the range
// of those b_i (no new extremum). Where the offsets' weighted mean is 0 (a point-symmetric
// neighbourhood: uniform grids) a is the area-weighted mean whatever g; elsewhere (graded
// meshes, where a large patch beside small ones pulls the mean by O(H |∇b|)) it is exact for
// a linear field. Fans whose centroids do not span the plane (a vertex on a surface's edge
// with two quads, a corner) keep the area-weighted mean: the smaller in-plane eigenvalue of
// the offsets' covariance must be at least kFitCondition of the larger.
Eigen::MatrixX3d linear_fit(const PatchMesh& mesh, const VertexField& f,
                            const Eigen::MatrixX3d& patch_values) {
  const Eigen::MatrixX3d mean = area_weighted(mesh, f, patch_values);
  std::vector<std::vector<std::int32_t>> around(f.size());
  for (std::int32_t i = 0; i < mesh.size(); ++i)
    for (int k = 0; k < mesh.patches[i].vertex_count; ++k)
      around[f.patch_corners[i][k]].push_back(i);
  Eigen::MatrixX3d values = mean;
  for (std::int32_t k = 0; k < f.size(); ++k) {
    const std::vector<std::int32_t>& ps = around[k];
    if (ps.size() < 3) continue;
    Eigen::Vector3d t, b;
    ff::orthonormal_frame(f.normals[k], t, b);
    double W = 0.0;
    Eigen::Vector2d Sd = Eigen::Vector2d::Zero();
    Eigen::Matrix2d Sdd = Eigen::Matrix2d::Zero();
    Eigen::RowVector3d Sb = Eigen::RowVector3d::Zero();
    Eigen::Matrix<double, 2, 3> Sdb = Eigen::Matrix<double, 2, 3>::Zero();
    Eigen::RowVector3d lo = patch_values.row(ps[0]), hi = lo;
    for (const std::int32_t i : ps) {
      const double w = mesh.patches[i].area;
      const Eigen::Vector3d d3 = mesh.patches[i].centroid - f.positions[k];
      const Eigen::Vector2d d(d3.dot(t), d3.dot(b));
      W += w;
      Sd += w * d;
      Sdd += w * d * d.transpose();
      Sb += w * patch_values.row(i);
      Sdb += w * d * patch_values.row(i);
      lo = lo.cwiseMin(patch_values.row(i));
      hi = hi.cwiseMax(patch_values.row(i));
    }
    if (!(W > 0.0)) continue;
    const Eigen::Matrix2d C = Sdd - Sd * Sd.transpose() / W;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(C);
    const double e0 = eig.eigenvalues()[0], e1 = eig.eigenvalues()[1];
    if (!(e1 > 0.0) || e0 < kFitCondition * e1) continue;
    const Eigen::Matrix<double, 2, 3> g = C.inverse() * (Sdb - Sd * Sb / W);
    const Eigen::RowVector3d a = (Sb - Sd.transpose() * g) / W;
    values.row(k) = a.cwiseMax(lo).cwiseMin(hi);
  }
  return values;
}

}  // namespace

VertexField interpolate_to_vertices(const PatchMesh& mesh, const Eigen::MatrixX3d& patch_values,
                                    VertexInterpolation mode, std::vector<SurfacePower>* power) {
  LAMBERT_CHECK(patch_values.rows() == mesh.size(), "patch field size does not match the mesh");
  VertexField f = build_shading_vertices(mesh);
  f.values = mode == VertexInterpolation::LinearFit ? linear_fit(mesh, f, patch_values)
                                                    : area_weighted(mesh, f, patch_values);
  anchor_hanging_vertices(find_hanging_vertices(mesh, f), f);

  std::vector<SurfacePower> pw = surface_power(mesh, patch_values, f);
  if (mode == VertexInterpolation::Conservative || mode == VertexInterpolation::LinearFit) {
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

VertexField exact_direct_vertex_field(const Scene& scene, const PatchMesh& mesh,
                                      const Eigen::MatrixX3d& patch_values,
                                      const Eigen::MatrixX3d& indirect, int threads,
                                      std::vector<SurfacePower>* power) {
  LAMBERT_CHECK(patch_values.rows() == mesh.size() && indirect.rows() == mesh.size(),
                "patch field size does not match the mesh");
  VertexField f = build_shading_vertices(mesh);
  Eigen::MatrixX3d E(mesh.size(), 3), rho(mesh.size(), 3);
  for (std::int32_t i = 0; i < mesh.size(); ++i) {
    E.row(i) = mesh.patches[i].emission.transpose();
    rho.row(i) = mesh.patches[i].rho.transpose();
  }
  const Eigen::MatrixX3d direct = exact_direct_irradiance(scene, f.positions, f.normals, threads);
  f.values =
      area_weighted(mesh, f, E).array() +
      area_weighted(mesh, f, rho).array() * (direct + area_weighted(mesh, f, indirect)).array();
  anchor_hanging_vertices(find_hanging_vertices(mesh, f), f);
  if (power) *power = surface_power(mesh, patch_values, f);
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

Eigen::Vector3d field_value(const PatchMesh& mesh, const VertexField& field, std::int32_t i,
                            const Eigen::Vector3d& p) {
  const auto w = patch_weights(mesh, i, p);
  const auto& c = field.patch_corners[i];
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int k = 0; k < mesh.patches[i].vertex_count; ++k)
    v += w[k] * field.values.row(c[k]).transpose();
  return v;
}

}  // namespace lambert
