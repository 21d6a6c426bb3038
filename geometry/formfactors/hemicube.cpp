// Estimator "hemicube": z-buffered projection onto a hemicube per patch (Cohen & Greenberg
// 1985). See hemicube.hpp for the equations and the known failure modes.
//
// Per row i, in the local frame (u, v, n) of patch i with origin c = centroid + offset·n,
// (u, v) rotated about n by an angle hashed from (seed, i) (see hemicube_row):
//  1. every other patch j with a corner in front of the tangent plane is transformed;
//     patches whose plane contains c (edge-on) cover no pixel and are skipped; patches
//     whose back faces c occlude but do not receive (item -1): only fronts receive;
//  2. for each of the five faces (view axis d, image axes a, b) the polygon is culled
//     against the face's frustum, clipped against the near plane w = d·r >= near, projected
//     to (a·r / w, b·r / w) and scan-converted at pixel centres (a half-open rule, so two
//     patches sharing an edge never both miss a pixel). The depth test uses the exact
//     distance to j's plane along the pixel's ray, 1/t = n_j·D / n_j·(p_j - c), which is
//     affine in the image coordinates (larger = nearer);
//  3. row i of F is the sum of ΔF over the pixels showing each patch.
// Complexity per row: O(N_patches) transforms + O(resolution²) pixels; memory per thread
// 3·resolution² (depth, item) pairs + one dense row accumulator of N_patches doubles.
// Thread safety: rows only write their own slots; buffers are per task.

#include "geometry/formfactors/hemicube.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sampling.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/formfactors/kernels.hpp"

namespace lambert::ff {
namespace {

// The hemicube origin is lifted off patch i by kRayOffset of the scene's diagonal
// (constants.hpp). It puts patches coplanar with i (its own surface) strictly behind the
// tangent plane, so they are excluded without a special case.
constexpr double kOffset = kRayOffset;
// Near-plane distance as a fraction of the offset. A face's frustum (|a|, |b| <= w) cut at
// w < near is a box of half-size near around c: only geometry within ~1e-9 of the diagonal
// from c is lost, and no other patch can come that close to c (it is 1e-6 off patch i).
// Keeping w >= near > 0 bounds the projected coordinates (<= diagonal / near ~ 1e9, exact
// enough in double precision).
constexpr double kNearFraction = 1e-3;
// A patch whose plane passes within kPlaneEps of the diagonal of c is edge-on: its
// projection is a segment covering no pixel centre, and its depth plane is singular.
constexpr double kEdgeOnEps = kPlaneEps;

// One hemicube face: view axis d and image axes a, b in the local frame (x=u, y=v, z=n).
struct Face {
  std::array<double, 3> d, a, b;
  bool top;  ///< top face: b in [-1, 1]; side faces: b in [0, 1]
};
constexpr std::array<Face, 5> kFaces = {{
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, true},
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, false},
    {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}, false},
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}, false},
    {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}, false},
}};

inline double dot3(const std::array<double, 3>& e, const Eigen::Vector3d& r) {
  return e[0] * r.x() + e[1] * r.y() + e[2] * r.z();
}

// The tangent frame (u, v) of a hemicube with unit normal n: u0 ⟂ n built from the world
// axis least aligned with n, then rotated about n by `angle` (radians); v = n × u.
void tangent_frame(const Eigen::Vector3d& n, double angle, Eigen::Vector3d& u,
                   Eigen::Vector3d& v) {
  int k = 0;
  for (int c = 1; c < 3; ++c)
    if (std::abs(n[c]) < std::abs(n[k])) k = c;
  const Eigen::Vector3d u0 = n.cross(Eigen::Vector3d::Unit(k)).normalized();
  const Eigen::Vector3d v0 = n.cross(u0);
  u = std::cos(angle) * u0 + std::sin(angle) * v0;
  v = n.cross(u);
}

// The z-buffer and item buffer of the five faces of one hemicube.
struct Buffers {
  int n = 0, m = 0;
  std::array<std::vector<double>, 5> depth;      // 1/t of the nearest surface; 0 = empty
  std::array<std::vector<std::int32_t>, 5> item;  // patch seen, -1 = none / back face
  std::int64_t pixels = 0;                        // depth tests made

  Buffers(int res, int rows) : n(res), m(rows) {
    for (size_t f = 0; f < kFaces.size(); ++f) {
      const size_t size = static_cast<size_t>(n) * (kFaces[f].top ? n : m);
      depth[f].resize(size);
      item[f].resize(size);
    }
  }
  void clear() {
    for (size_t f = 0; f < kFaces.size(); ++f) {
      std::fill(depth[f].begin(), depth[f].end(), 0.0);
      std::fill(item[f].begin(), item[f].end(), -1);
    }
  }
};

// A polygon in one face's coordinates: (a, b, w) per vertex before projection.
constexpr int kMaxVerts = 8;  // a quad clipped by one plane has at most 5 vertices
struct Poly {
  double a[kMaxVerts], b[kMaxVerts], w[kMaxVerts];
  int count = 0;
};

// True when the convex polygon lies entirely outside one of the planes through c that
// bound face f's frustum (|a| <= w, |b| <= w or 0 <= b <= w for sides, w >= near).
bool outside_frustum(const Poly& p, bool top, double near) {
  bool all_near = true, all_ap = true, all_an = true, all_bp = true, all_bn = true;
  for (int k = 0; k < p.count; ++k) {
    all_near = all_near && p.w[k] < near;
    all_ap = all_ap && p.a[k] > p.w[k];
    all_an = all_an && p.a[k] < -p.w[k];
    all_bp = all_bp && p.b[k] > p.w[k];
    all_bn = all_bn && (top ? p.b[k] < -p.w[k] : p.b[k] <= 0.0);
  }
  return all_near || all_ap || all_an || all_bp || all_bn;
}

// Sutherland-Hodgman clip against w >= near.
Poly clip_near(const Poly& in, double near) {
  Poly out;
  for (int k = 0; k < in.count; ++k) {
    const int l = (k + 1) % in.count;
    const bool kin = in.w[k] >= near, lin = in.w[l] >= near;
    if (kin) {
      out.a[out.count] = in.a[k];
      out.b[out.count] = in.b[k];
      out.w[out.count++] = in.w[k];
    }
    if (kin != lin) {
      const double t = (near - in.w[k]) / (in.w[l] - in.w[k]);
      out.a[out.count] = in.a[k] + t * (in.a[l] - in.a[k]);
      out.b[out.count] = in.b[k] + t * (in.b[l] - in.b[k]);
      out.w[out.count++] = near;
    }
  }
  return out;
}

// First pixel index whose centre lo + (k + ½) step is >= x, clamped to [0, count].
inline int first_center_at_or_after(double x, double lo, double step, int count) {
  const double k = std::ceil((x - lo) / step - 0.5);
  return static_cast<int>(std::clamp(k, 0.0, static_cast<double>(count)));
}

// Scan-converts the projected convex polygon (xs, ys) into face f: pixel centres with
// ymin <= y < ymax and xl <= x < xr (half-open) take `id` where 1/t = α x + β y + γ is
// larger than the stored depth.
void rasterise(const double* xs, const double* ys, int count, int f, double alpha, double beta,
               double gamma, std::int32_t id, Buffers& buf) {
  const int cols = buf.n;
  const int rows = kFaces[f].top ? buf.n : buf.m;
  const double dx = 2.0 / cols;
  const double y0 = kFaces[f].top ? -1.0 : 0.0;
  const double dy = kFaces[f].top ? 2.0 / rows : 1.0 / rows;
  double ymin = ys[0], ymax = ys[0];
  for (int k = 1; k < count; ++k) {
    ymin = std::min(ymin, ys[k]);
    ymax = std::max(ymax, ys[k]);
  }
  const int r0 = first_center_at_or_after(ymin, y0, dy, rows);
  const int r1 = first_center_at_or_after(ymax, y0, dy, rows);
  double* depth = buf.depth[f].data();
  std::int32_t* item = buf.item[f].data();
  for (int r = r0; r < r1; ++r) {
    const double y = y0 + (r + 0.5) * dy;
    double xl = std::numeric_limits<double>::infinity(), xr = -xl;
    for (int k = 0; k < count; ++k) {
      const int l = k + 1 == count ? 0 : k + 1;
      if ((ys[k] <= y) == (ys[l] <= y)) continue;
      const double x = xs[k] + (y - ys[k]) * (xs[l] - xs[k]) / (ys[l] - ys[k]);
      xl = std::min(xl, x);
      xr = std::max(xr, x);
    }
    if (!(xl < xr)) continue;
    const int c0 = first_center_at_or_after(xl, -1.0, dx, cols);
    const int c1 = first_center_at_or_after(xr, -1.0, dx, cols);
    const double row_depth = beta * y + gamma;
    const size_t base = static_cast<size_t>(r) * cols;
    for (int c = c0; c < c1; ++c) {
      const double z = alpha * (-1.0 + (c + 0.5) * dx) + row_depth;
      if (z > depth[base + c]) {
        depth[base + c] = z;
        item[base + c] = id;
      }
    }
    buf.pixels += c1 - c0;
  }
}

// Projects patch g (with item id) onto the five faces around origin c in frame (u, v, n).
void project_patch(const PatchGeom& g, std::int32_t id, const Eigen::Vector3d& c,
                   const Eigen::Matrix3d& to_local, double near, Buffers& buf) {
  Eigen::Vector3d r[4];
  for (int k = 0; k < g.n; ++k) r[k] = to_local * (g.p[k] - c);
  const Eigen::Vector3d m = to_local * g.normal;  // j's normal in the local frame
  const double num = m.dot(to_local * (g.centroid - c));
  for (int f = 0; f < static_cast<int>(kFaces.size()); ++f) {
    const Face& face = kFaces[f];
    Poly p;
    p.count = g.n;
    for (int k = 0; k < g.n; ++k) {
      p.a[k] = dot3(face.a, r[k]);
      p.b[k] = dot3(face.b, r[k]);
      p.w[k] = dot3(face.d, r[k]);
    }
    if (outside_frustum(p, face.top, near)) continue;
    const Poly q = clip_near(p, near);
    if (q.count < 3) continue;
    double xs[kMaxVerts], ys[kMaxVerts];
    for (int k = 0; k < q.count; ++k) {
      xs[k] = q.a[k] / q.w[k];
      ys[k] = q.b[k] / q.w[k];
    }
    // 1/t along D = x a + y b + d from c to j's plane: n_j·D / n_j·(p_j - c).
    const double alpha = dot3(face.a, m) / num;
    const double beta = dot3(face.b, m) / num;
    const double gamma = dot3(face.d, m) / num;
    rasterise(xs, ys, q.count, f, alpha, beta, gamma, id, buf);
  }
}

struct HemicubeEntry {
  std::int32_t j;
  double f;
};

// Row i: render every other patch into the hemicube of i and sum the delta form factors.
void hemicube_row(const std::vector<PatchGeom>& geom, std::int32_t i, const HemicubeDeltas& dF,
                  double offset, double edge_eps, std::uint64_t seed, Buffers& buf,
                  std::vector<double>& acc, std::vector<HemicubeEntry>& row) {
  const PatchGeom& gi = geom[i];
  const Eigen::Vector3d c = gi.centroid + offset * gi.normal;
  Eigen::Vector3d u, v;
  // A per-row pseudo-random rotation about the normal (a pure function of seed and i):
  // without it, axis-aligned scenes put projected edges exactly through rows of pixel
  // centres (e.g. the 45° silhouettes of a neighbour sharing an edge) and the half-open
  // coverage rule turns them into a first-order bias of the same sign in every row; rotated,
  // the aliasing error is zero-mean noise that falls faster with N and averages out.
  const double angle = 2.0 * M_PI * to_unit(hash_keys(seed, static_cast<std::uint64_t>(i)));
  tangent_frame(gi.normal, angle, u, v);
  Eigen::Matrix3d to_local;
  to_local.row(0) = u.transpose();
  to_local.row(1) = v.transpose();
  to_local.row(2) = gi.normal.transpose();
  const double near = kNearFraction * offset;
  buf.clear();
  const auto n = static_cast<std::int32_t>(geom.size());
  for (std::int32_t j = 0; j < n; ++j) {
    if (j == i) continue;
    const PatchGeom& g = geom[j];
    bool in_front = false;
    for (int k = 0; k < g.n && !in_front; ++k) in_front = gi.normal.dot(g.p[k] - c) > 0.0;
    if (!in_front) continue;  // wholly behind the tangent plane: neither seen nor occluding
    const double facing = g.normal.dot(c - g.centroid);
    if (std::abs(facing) <= edge_eps) continue;  // edge-on
    project_patch(g, facing > 0.0 ? j : -1, c, to_local, near, buf);
  }
  for (size_t f = 0; f < kFaces.size(); ++f) {
    const std::vector<double>& w = kFaces[f].top ? dF.top : dF.side;
    const std::vector<std::int32_t>& item = buf.item[f];
    for (size_t p = 0; p < item.size(); ++p)
      if (item[p] >= 0) acc[item[p]] += w[p];
  }
  row.clear();
  for (std::int32_t j = 0; j < n; ++j) {
    if (acc[j] == 0.0) continue;
    row.push_back({j, acc[j]});
    acc[j] = 0.0;
  }
}

}  // namespace

double HemicubeDeltas::total() const {
  double t = 0.0, s = 0.0;
  for (double x : top) t += x;
  for (double x : side) s += x;
  return t + 4.0 * s;
}

HemicubeDeltas hemicube_deltas(int resolution) {
  LAMBERT_CHECK(resolution >= 2, "hemicube resolution must be at least 2");
  HemicubeDeltas d;
  d.n = resolution;
  d.m = (resolution + 1) / 2;
  const double dx = 2.0 / d.n;
  d.top.resize(static_cast<size_t>(d.n) * d.n);
  for (int r = 0; r < d.n; ++r) {
    const double y = -1.0 + (r + 0.5) * dx;
    for (int c = 0; c < d.n; ++c) {
      const double x = -1.0 + (c + 0.5) * dx;
      const double q = x * x + y * y + 1.0;
      d.top[static_cast<size_t>(r) * d.n + c] = dx * dx / (M_PI * q * q);
    }
  }
  const double dz = 1.0 / d.m;
  d.side.resize(static_cast<size_t>(d.m) * d.n);
  for (int r = 0; r < d.m; ++r) {
    const double z = (r + 0.5) * dz;
    for (int c = 0; c < d.n; ++c) {
      const double y = -1.0 + (c + 0.5) * dx;
      const double q = y * y + z * z + 1.0;
      d.side[static_cast<size_t>(r) * d.n + c] = z * dx * dz / (M_PI * q * q);
    }
  }
  return d;
}

FormFactors compute_hemicube(const PatchMesh& mesh, const FormFactorOptions& options,
                             HemicubeStats* hemicube_stats) {
  if (options.hemicube.resolution < 2) throw UsageError("--hemicube-res must be at least 2");
  Timer timer;
  const std::int32_t n = mesh.size();
  const std::vector<PatchGeom> geom = patch_geometry(mesh);
  const HemicubeDeltas dF = hemicube_deltas(options.hemicube.resolution);
  const double offset = kOffset * mesh.scale;
  const double edge_eps = kEdgeOnEps * mesh.scale;

  std::vector<std::vector<HemicubeEntry>> rows(n);
  std::vector<std::int64_t> tested(n, 0), pixels(n, 0);
  Progress progress("hemicube", options.run.progress ? n : 0, "px");
  // Chunks of 4 rows: buffers are allocated once per chunk (3·res² pixels), while chunks
  // stay small enough to balance rows of uneven cost.
  parallel_for(n, 4, options.run.threads, [&](std::int64_t begin, std::int64_t end) {
    Buffers buf(dF.n, dF.m);
    std::vector<double> acc(n, 0.0);
    for (std::int64_t ii = begin; ii < end; ++ii) {
      const auto i = static_cast<std::int32_t>(ii);
      if (!options.subset.only.empty() && !options.subset.only[i]) continue;
      buf.pixels = 0;
      hemicube_row(geom, i, dF, offset, edge_eps, options.run.seed, buf, acc, rows[i]);
      rows[i].shrink_to_fit();
      for (std::int32_t j = i + 1; j < n; ++j)
        tested[i] += can_exchange(geom[i], geom[j], edge_eps);
      pixels[i] = buf.pixels;
      progress.advance(1, buf.pixels);
    }
  });
  progress.finish();

  FormFactors out;
  out.options = options;
  std::int64_t nnz = 0, total_pixels = 0;
  for (std::int32_t i = 0; i < n; ++i) {
    out.stats.pairs_tested += tested[i];
    total_pixels += pixels[i];
    nnz += static_cast<std::int64_t>(rows[i].size());
  }
  out.stats.pairs_culled = static_cast<std::int64_t>(n) * (n - 1) / 2 - out.stats.pairs_tested;
  if (hemicube_stats) hemicube_stats->pixels = total_pixels;
  SparseF F(n, n);
  F.resizeNonZeros(nnz);
  std::int64_t at = 0;
  for (std::int32_t i = 0; i < n; ++i) {
    F.outerIndexPtr()[i] = at;
    for (const HemicubeEntry& e : rows[i]) {
      F.innerIndexPtr()[at] = e.j;
      F.valuePtr()[at++] = e.f;
    }
    std::vector<HemicubeEntry>().swap(rows[i]);  // release memory as we go
  }
  F.outerIndexPtr()[n] = at;
  out.F.swap(F);  // Eigen 3.4 sparse matrices have no move: std::move would copy
  out.stats.seconds = timer.seconds();
  return out;
}

}  // namespace lambert::ff
