#include "geometry/hierarchical/hierarchical.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <tuple>
#include <unordered_map>

#include "core/error.hpp"
#include "core/memory.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/timer.hpp"
#include "geometry/formfactors/constants.hpp"
#include "geometry/hierarchical/hierarchy.hpp"
#include "geometry/hierarchical/links.hpp"
#include "geometry/visibility/bvh.hpp"

namespace lambert {
namespace {

using hr::Action;
using hr::Hierarchy;
using hr::Link;

/// Relative element area bound when --min-area is 0: 1e-5 of the total area lets a surface
/// of 1 % of the scene split to ~1000 leaves, the resolution of a fine uniform mesh.
constexpr double kAutoMinAreaFraction = 1e-5;

/// Chunk sizes of the parallel loops (items per task): big enough to amortise scheduling,
/// small enough to balance 2-64 threads.
constexpr std::int64_t kEvalChunk = 256;
constexpr std::int64_t kGatherChunk = 1024;

void check_options(const HierarchicalOptions& o) {
  if (!(o.epsilon > 0.0 && o.epsilon < 1.0))
    throw UsageError("--epsilon must be in (0, 1), got " + std::to_string(o.epsilon));
  if (!(o.min_area >= 0.0 && std::isfinite(o.min_area)))
    throw UsageError("--min-area must be a finite number >= 0");
  if (o.link_rays < 1 || o.link_rays > 4096)
    throw UsageError("--link-rays must be in [1, 4096], got " + std::to_string(o.link_rays));
  if (!(o.tol > 0.0 && o.tol < 1.0)) throw UsageError("--tol must be in (0, 1)");
  if (o.max_iterations < 1) throw UsageError("--max-iter must be >= 1");
  if (o.max_passes < 1) throw UsageError("the number of refinement passes must be >= 1");
}

/// The irradiance a node gathers or inherits, per channel: at an element, its values at the
/// corners ([0, 4): linear on triangles, bilinear on quads); at a cluster, the irradiance
/// per unit projected area arriving from each of the six axis directions (the bins of
/// Node::facing). An element below a cluster receives sum_b E_b max(0, n · e_b).
using Field = std::array<Eigen::Vector3d, 6>;
const Field kNoField = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                        Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                        Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
using Corners = Field;  // an element's field: entries 0..3

/// The per-node state of the solution: radiosity B (area average below the node), the
/// irradiance gathered over the node's own links, and for leaves the total irradiance.
struct State {
  std::vector<Eigen::Vector3d> B, H;
  std::vector<Field> gathered;  ///< over the node's own links
  std::vector<Eigen::Vector3d> lo, hi;  ///< per channel min and max of the leaves' B below
  std::vector<Eigen::Matrix3d> grad;    ///< elements: gradient of B (row = channel), in plane
  /// B of node q read at offset d from its centroid (its linear fit, kept within [lo, hi]).
  Eigen::Vector3d read(std::int32_t q, const float* d) const {
    const Eigen::Vector3d offset(d[0], d[1], d[2]);
    return (B[q] + grad[q] * offset).cwiseMax(lo[q]).cwiseMin(hi[q]);
  }
  /// What the oracle knows of q's radiosity.
  hr::SourceB source(std::int32_t q) const {
    return {B[q].maxCoeff(), (hi[q] - lo[q]).maxCoeff(), hi[q].maxCoeff()};
  }
  /// Bytes of state per node (for the memory count).
  static constexpr double kBytesPerNode =
      4 * sizeof(Eigen::Vector3d) + sizeof(Eigen::Matrix3d) + sizeof(Field);
  /// Bytes held (by capacity).
  double bytes() const { return static_cast<double>(B.capacity()) * kBytesPerNode; }
  void reserve(std::size_t n) {
    lo.reserve(n);
    grad.reserve(n);
    hi.reserve(n);
    B.reserve(n);
    gathered.reserve(n);
    H.reserve(n);
  }
  void resize(std::size_t n) {
    lo.resize(n, Eigen::Vector3d::Zero());
    grad.resize(n, Eigen::Matrix3d::Zero());
    hi.resize(n, Eigen::Vector3d::Zero());
    B.resize(n, Eigen::Vector3d::Zero());
    gathered.resize(n, kNoField);
    H.resize(n, Eigen::Vector3d::Zero());
  }
};

/// Least-squares gradient (rows: channels) in the plane with unit normal n of values v_k at
/// points x_k with weights w_k: the linear fit v = v̄ + g (x - x̄). Zero when the points do
/// not span the plane.
Eigen::Matrix3d plane_gradient(const Eigen::Vector3d& n, const Eigen::Vector3d* x,
                               const Eigen::Vector3d* v, const double* w, int count) {
  const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  double sw = 0.0;
  Eigen::Vector3d xm = Eigen::Vector3d::Zero(), vm = Eigen::Vector3d::Zero();
  for (int k = 0; k < count; ++k) {
    sw += w[k];
    xm += w[k] * x[k];
    vm += w[k] * v[k];
  }
  if (!(sw > 0.0)) return Eigen::Matrix3d::Zero();
  xm /= sw;
  vm /= sw;
  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();
  Eigen::Matrix<double, 2, 3> R = Eigen::Matrix<double, 2, 3>::Zero();
  for (int k = 0; k < count; ++k) {
    const Eigen::Vector2d a(t1.dot(x[k] - xm), t2.dot(x[k] - xm));
    M += w[k] * a * a.transpose();
    R += w[k] * a * (v[k] - vm).transpose();
  }
  // Degenerate (collinear) point sets: no gradient rather than an ill-conditioned one.
  if (!(M.determinant() > 1e-12 * M.squaredNorm())) return Eigen::Matrix3d::Zero();
  const Eigen::Matrix<double, 2, 3> g = M.inverse() * R;  // rows: in-plane directions
  Eigen::Matrix3d out;
  for (int c = 0; c < 3; ++c) out.row(c) = (g(0, c) * t1 + g(1, c) * t2).transpose();
  return out;
}

/// The corner values of child k of element i (split_element's order) interpolated from i's:
/// edge midpoints average two corners, a quad's centre all four (exact for the linear and
/// bilinear fields, the children being sub-triangles and parameter sub-squares).
Corners child_corners(const Corners& c, int n, int k) {
  auto m = [&](int a, int b) -> Eigen::Vector3d { return 0.5 * (c[a] + c[b]); };
  const Eigen::Vector3d o = Eigen::Vector3d::Zero();
  if (n == 3) {
    switch (k) {
      case 0: return {c[0], m(0, 1), m(2, 0), o, o, o};
      case 1: return {m(0, 1), c[1], m(1, 2), o, o, o};
      case 2: return {m(2, 0), m(1, 2), c[2], o, o, o};
      default: return {m(1, 2), m(2, 0), m(0, 1), o, o, o};
    }
  }
  const Eigen::Vector3d centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  switch (k) {
    case 0: return {c[0], m(0, 1), centre, m(3, 0), o, o};
    case 1: return {m(0, 1), c[1], m(1, 2), centre, o, o};
    case 2: return {centre, m(1, 2), c[2], m(2, 3), o, o};
    default: return {m(3, 0), centre, m(2, 3), c[3], o, o};
  }
}

/// The irradiance an element with unit normal n receives from a cluster's directional field.
Eigen::Vector3d facing_irradiance(const Field& E, const Eigen::Vector3d& n) {
  Eigen::Vector3d H = Eigen::Vector3d::Zero();
  for (int a = 0; a < 3; ++a) {
    H += std::max(0.0, n[a]) * E[2 * a];
    H += std::max(0.0, -n[a]) * E[2 * a + 1];
  }
  return H;
}

/// Push-pull: irradiance down (a cluster hands the directional field it and its ancestors
/// gathered to its children, which take what their faces' orientation lets them; an element
/// adds its own gathered corner field to the inherited one and hands each child the
/// interpolated field), B = E + rho mean(H) at the leaves, area-averaged B up. A sweep
/// returns the largest change of a leaf's B and the largest leaf B (any channel).
struct Sweep {
  double change = 0.0, max_b = 0.0;
  void add(const Sweep& o) {
    change = std::max(change, o.change);
    max_b = std::max(max_b, o.max_b);
  }
};

/// The field child k of node i (whose total field is H) inherits.
Field child_down(const Hierarchy& h, std::int32_t i, const Field& H, int k) {
  const hr::Node& n = h.node(i);
  const std::int32_t c = h.child(i, k);
  if (!n.cluster) return child_corners(H, h.geom(i).n, k);
  if (h.node(c).cluster) return H;
  const Eigen::Vector3d e = facing_irradiance(H, h.geom(c).normal);
  Field down = kNoField;
  for (int j = 0; j < 4; ++j) down[j] = e;
  return down;
}

/// A leaf's B (and its spread and gradient) from its total field H.
Sweep update_leaf(const Hierarchy& h, std::int32_t i, const Field& H, State& s) {
  const int corners = h.geom(i).n;
  const Patch& face = h.faces().patches[h.node(i).face];
  const std::array<double, 4> mu = hr::corner_masses(h.geom(i));
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int k = 0; k < corners; ++k) mean += mu[k] * H[k];
  const Eigen::Vector3d b = face.emission + face.rho.cwiseProduct(mean);
  const double change = (b - s.B[i]).cwiseAbs().maxCoeff();
  s.B[i] = b;
  // The spread of B over the leaf: its irradiance varies between the corner values.
  s.lo[i] = b;
  s.hi[i] = b;
  Eigen::Vector3d bk[4];
  for (int k = 0; k < corners; ++k) {
    bk[k] = face.emission + face.rho.cwiseProduct(H[k]);
    s.lo[i] = s.lo[i].cwiseMin(bk[k]);
    s.hi[i] = s.hi[i].cwiseMax(bk[k]);
  }
  const ff::PatchGeom& g = h.geom(i);
  s.grad[i] = plane_gradient(g.normal, g.p.data(), bk, mu.data(), corners);
  s.H[i] = mean;
  return {change, b.maxCoeff()};
}

/// An inner node's B (area average), spread and gradient from its children's.
void pull(const Hierarchy& h, std::int32_t i, State& s) {
  const hr::Node& n = h.node(i);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();
  for (int k = 0; k < n.child_count; ++k) {
    const std::int32_t c = h.child(i, k);
    sum += h.node(c).area * s.B[c];
    lo = lo.cwiseMin(s.lo[c]);
    hi = hi.cwiseMax(s.hi[c]);
  }
  s.lo[i] = lo;
  s.hi[i] = hi;
  s.B[i] = sum / n.area;
  if (!n.cluster) {
    Eigen::Vector3d x[4], v[4];
    double w[4];
    for (int k = 0; k < n.child_count; ++k) {
      const std::int32_t c = h.child(i, k);
      x[k] = h.geom(c).centroid;
      v[k] = s.B[c];
      w[k] = h.node(c).area;
    }
    s.grad[i] = plane_gradient(h.geom(i).normal, x, v, w, n.child_count);
  }
}

/// The total field of node i: what it inherits plus what it gathered over its own links.
Field total_field(std::int32_t i, const Field& down, const State& s) {
  Field H;
  for (int k = 0; k < 6; ++k) H[k] = down[k] + s.gathered[i][k];
  return H;
}

/// Push-pull of the subtree below node i, which inherits `down`.
Sweep push_pull(const Hierarchy& h, std::int32_t i, const Field& down, State& s) {
  const Field H = total_field(i, down, s);
  if (h.is_leaf(i)) return update_leaf(h, i, H, s);
  Sweep sweep;
  for (int k = 0; k < h.node(i).child_count; ++k)
    sweep.add(push_pull(h, h.child(i, k), child_down(h, i, H, k), s));
  pull(h, i, s);
  return sweep;
}

/// The push-pull of the whole tree on several threads: the nodes whose subtrees exceed
/// `grain` nodes (the top) push their fields down serially, the subtrees below them run
/// push_pull in parallel, then the top pulls B up. Each node's arithmetic is push_pull's,
/// so B is bitwise the serial sweep's for any thread count.
class ParallelPushPull {
 public:
  ParallelPushPull(const Hierarchy& h, int threads) : h_(h), threads_(threads) {
    // Subtree sizes, children after parents in node order except below clusters: an
    // explicit post-order.
    size_.assign(h.nodes().size(), 1);
    std::vector<std::pair<std::int32_t, bool>> stack{{h.root(), false}};
    while (!stack.empty()) {
      const auto [i, done] = stack.back();
      stack.pop_back();
      const int children = h.node(i).child_count;
      if (done) {
        for (int k = 0; k < children; ++k) size_[i] += size_[h.child(i, k)];
        continue;
      }
      stack.emplace_back(i, true);
      for (int k = 0; k < children; ++k) stack.emplace_back(h.child(i, k), false);
    }
    // Subtrees of ~1/16 of a thread's share: enough pieces to balance uneven ones.
    grain_ = std::max<std::int64_t>(4096, static_cast<std::int64_t>(h.nodes().size()) /
                                              (16 * static_cast<std::int64_t>(threads)));
  }

  Sweep operator()(State& s) {
    if (threads_ <= 1 || size_[h_.root()] <= grain_) return push_pull(h_, h_.root(), kNoField, s);
    tasks_.clear();
    descend(h_.root(), kNoField, s);
    std::vector<Sweep> swept(tasks_.size());
    parallel_for(static_cast<std::int64_t>(tasks_.size()), 1, threads_,
                 [&](std::int64_t begin, std::int64_t end) {
                   for (std::int64_t t = begin; t < end; ++t)
                     swept[t] = push_pull(h_, tasks_[t].first, tasks_[t].second, s);
                 });
    ascend(h_.root(), s);
    Sweep sweep;
    for (const Sweep& x : swept) sweep.add(x);
    return sweep;
  }

 private:
  bool top(std::int32_t i) const { return size_[i] > grain_; }
  void descend(std::int32_t i, const Field& down, const State& s) {
    if (!top(i)) {
      tasks_.emplace_back(i, down);
      return;
    }
    const Field H = total_field(i, down, s);
    for (int k = 0; k < h_.node(i).child_count; ++k)
      descend(h_.child(i, k), child_down(h_, i, H, k), s);
  }
  void ascend(std::int32_t i, State& s) {
    if (!top(i)) return;
    for (int k = 0; k < h_.node(i).child_count; ++k) ascend(h_.child(i, k), s);
    pull(h_, i, s);
  }

  const Hierarchy& h_;
  int threads_;
  std::vector<std::int64_t> size_;
  std::int64_t grain_ = 0;
  std::vector<std::pair<std::int32_t, Field>> tasks_;
};

/// Links in arrays that parallel loops fill (no zeroing pass before them).
using LinkArray = std::vector<Link, UninitializedAllocator<Link>>;

/// Links sorted by receiver (and source: every (p, q) pair is one link), with the start of
/// each receiver's run, and the links accepted since they were sorted.
struct LinkTable {
  LinkArray links;                   ///< sorted by (p, q)
  std::vector<std::int64_t> starts;  ///< run k is links[starts[k], starts[k+1])
  std::vector<LinkArray> fresh;      ///< accepted since the last index, one array per wave
  /// The table before the last index: the next index merges into it (its pages are already
  /// the process's: a fresh array of every link each pass faulted them in again).
  LinkArray spare;

  std::size_t fresh_links() const {
    std::size_t m = 0;
    for (const LinkArray& wave : fresh) m += wave.size();
    return m;
  }
  /// The array a merged table of n links gets where the spare is too small: a quarter more
  /// (the table grows from pass to pass; the spare is reused while it holds the next one)
  /// unless `tight`.
  static std::size_t merged_capacity(std::size_t n, bool tight) { return tight ? n : n + n / 4; }
  /// Bytes the index needs beside what is held: the fresh links side by side and the
  /// merged table (where the spare is too small for it).
  double index_bytes(bool tight) const {
    const std::size_t n = links.size() + fresh_links();
    return static_cast<double>(fresh_links() +
                               (spare.capacity() < n ? merged_capacity(n, tight) : 0)) *
           sizeof(Link);
  }
  /// Sorts the fresh links and merges them into the table on `threads` threads (the order
  /// is the one std::sort gives, (p, q) pairs being unique).
  void index(int threads, bool tight) {
    const auto less = [](const Link& a, const Link& b) {
      return a.p < b.p || (a.p == b.p && a.q < b.q);
    };
    const std::int64_t m = static_cast<std::int64_t>(fresh_links());
    if (m > 0) {
      const std::int64_t head = static_cast<std::int64_t>(links.size()), n = head + m;
      LinkArray tail(static_cast<std::size_t>(m));
      std::vector<std::int64_t> at(fresh.size() + 1, 0);
      for (std::size_t w = 0; w < fresh.size(); ++w)
        at[w + 1] = at[w] + static_cast<std::int64_t>(fresh[w].size());
      parallel_for(static_cast<std::int64_t>(fresh.size()), 1, threads,
                   [&](std::int64_t begin, std::int64_t end) {
                     for (std::int64_t w = begin; w < end; ++w) {
                       std::copy(fresh[w].begin(), fresh[w].end(), tail.begin() + at[w]);
                       LinkArray().swap(fresh[w]);
                     }
                   });
      fresh.clear();
      LinkArray merged;  // the sort's buffer, then the result
      merged.swap(spare);
      if (merged.capacity() < static_cast<std::size_t>(n)) {
        LinkArray().swap(merged);
        merged.reserve(merged_capacity(static_cast<std::size_t>(n), tight));
      }
      merged.resize(static_cast<std::size_t>(n));
      parallel_sort(tail.data(), m, less, threads, merged.data());
      parallel_merge(links.data(), head, tail.data(), m, merged.data(), less, threads);
      links.swap(merged);
      spare.swap(merged);
    }
    starts.clear();
    for (std::size_t k = 0; k < links.size(); ++k)
      if (k == 0 || links[k].p != links[k - 1].p) starts.push_back(static_cast<std::int64_t>(k));
    starts.push_back(static_cast<std::int64_t>(links.size()));
  }
};

/// gathered[p] = sum over p's links of c_pq B_q (per corner; q read at the link's point); for
/// a cluster p, the power F_pq B_q A_p of each link split by the link's orientation bins, as
/// irradiance per unit projected area of the faces in each bin. In link order
/// (deterministic).
void gather(const Hierarchy& h, const LinkTable& t, State& s, int threads) {
  std::fill(s.gathered.begin(), s.gathered.end(), kNoField);
  const std::int64_t runs = static_cast<std::int64_t>(t.starts.size()) - 1;
  parallel_for(runs, kGatherChunk, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t r = begin; r < end; ++r) {
      const std::int32_t p = t.links[t.starts[r]].p;
      const hr::Node& np = h.node(p);
      Field sum = kNoField;
      for (std::int64_t k = t.starts[r]; k < t.starts[r + 1]; ++k) {
        const Link& l = t.links[k];
        const Eigen::Vector3d b = s.read(l.q, l.d);
        if (!np.cluster) {
          for (int c = 0; c < 4; ++c) sum[c] += static_cast<double>(l.c[c]) * b;
          continue;
        }
        const Eigen::Vector3d power = static_cast<double>(l.F) * np.area * b;
        for (int bin = 0; bin < 6; ++bin)
          if (l.bins[bin] > 0.0f && np.facing[bin] > 0.0)
            sum[bin] += power * (static_cast<double>(l.bins[bin]) / np.facing[bin]);
      }
      s.gathered[p] = sum;
    }
  });
}

/// A link to refine and how.
struct Refinement {
  std::int32_t p, q;
  Action action;
};

/// The child links of refined links (after their nodes were split), in order; `count` is
/// their number (wave_size), reserved up front.
std::vector<std::pair<std::int32_t, std::int32_t>> expand(const Hierarchy& h,
                                                          const std::vector<Refinement>& r,
                                                          std::size_t count) {
  std::vector<std::pair<std::int32_t, std::int32_t>> out;
  out.reserve(count);
  for (const auto& x : r) {
    const hr::Node& np = h.node(x.p);
    const hr::Node& nq = h.node(x.q);
    if (x.action == Action::SplitBoth) {
      for (int a = 0; a < np.child_count; ++a)
        for (int b = 0; b < np.child_count; ++b) out.emplace_back(h.child(x.p, a), h.child(x.p, b));
    } else if (x.action == Action::SplitReceiver) {
      for (int a = 0; a < np.child_count; ++a) out.emplace_back(h.child(x.p, a), x.q);
    } else {
      for (int b = 0; b < nq.child_count; ++b) out.emplace_back(x.p, h.child(x.q, b));
    }
  }
  return out;
}

/// Gives the unsplit elements a wave refines (`nodes`, sorted and unique: wave_size) their
/// children, in increasing node order (so node numbers do not depend on threads),
/// initialising their B from the parent's.
void split_nodes(Hierarchy& h, const std::vector<std::int32_t>& nodes, State& s) {
  const std::int32_t first_new = h.size();
  for (const std::int32_t i : nodes) {
    if (h.size() > std::numeric_limits<std::int32_t>::max() - 8)
      throw Error("hierarchical: more than 2^31 nodes; raise --epsilon or --min-area");
    h.split_element(i);
  }
  s.resize(h.nodes().size());
  for (const std::int32_t i : nodes)
    for (int k = 0; k < h.node(i).child_count; ++k) {
      const std::int32_t c = h.child(i, k);
      if (c >= first_new) s.B[c] = s.lo[c] = s.hi[c] = s.B[i];
    }
}

/// The refinement's memory: what it holds, and what the next wave or recheck would add at
/// its peak, so that a hierarchy that would exceed the limit stops before allocating (the
/// limit bounds the peak, not the state after a wave). Every growing vector is reserved to
/// the size the estimate assumed, so it is reallocated at most once per wave and the peak is
/// the old buffer plus the new one.
struct Budget {
  const Hierarchy& h;
  const LinkTable& t;
  const State& s;
  double limit;  ///< bytes (0 = none)

  /// Bytes held now: nodes with geometry and state, links and their index, the face BVH.
  double held() const {
    double fresh = 0.0;
    for (const LinkArray& wave : t.fresh) fresh += static_cast<double>(wave.capacity());
    return h.bytes() + s.bytes() +
           static_cast<double>(t.links.capacity() + t.spare.capacity() + fresh) * sizeof(Link) +
           static_cast<double>(t.starts.capacity()) * sizeof(std::int64_t) +
           static_cast<double>(h.faces().size()) * 256.0;  // the face BVH, ~2 nodes per face
  }
  /// The capacity a vector of `size` and `capacity` is reserved to before growing by `add`
  /// (amortised: at least 1.5x, so a long refinement copies O(n) in all).
  static std::size_t grown(std::size_t size, std::size_t capacity, std::size_t add) {
    return size + add <= capacity ? capacity : std::max(size + add, capacity + capacity / 2);
  }
  /// Throws when the held bytes plus `extra` exceed the limit.
  void check(double extra, const char* stage) const {
    const double need = held() + extra;
    if (limit > 0 && need > limit)
      throw Error("hierarchical: the hierarchy needs more than " + format_bytes(limit) + " (" +
                  format_bytes(need) + " at its " + stage + ": " + std::to_string(h.size()) +
                  " nodes, " + std::to_string(t.links.size()) +
                  " links so far); raise --epsilon or --min-area, or the memory limit");
  }
};

/// Node children and child links a wave over `r` creates: (nodes split, child links).
std::pair<std::size_t, std::size_t> wave_size(const Hierarchy& h, const std::vector<Refinement>& r,
                                              std::vector<std::int32_t>& split) {
  split.clear();
  std::size_t links = 0;
  const auto children = [&](std::int32_t i) -> std::size_t {
    const hr::Node& n = h.node(i);
    if (n.child_count > 0 || n.cluster) return static_cast<std::size_t>(n.child_count);
    split.push_back(i);
    return 4;  // split_element makes 4
  };
  for (const auto& x : r) {
    if (x.action == Action::SplitBoth) {
      const std::size_t c = children(x.p);
      links += c * c;
    } else {
      links += children(x.action == Action::SplitSource ? x.q : x.p);
    }
  }
  std::sort(split.begin(), split.end());
  split.erase(std::unique(split.begin(), split.end()), split.end());
  return {split.size() * 4, links};
}

/// The leaves as a PatchMesh (vertices shared within a surface by exact position) and B.
void export_leaves(const Hierarchy& h, const State& s, const std::vector<double>& error,
                   HierarchicalResult& out) {
  const PatchMesh& faces = h.faces();
  PatchMesh& mesh = out.mesh;
  mesh.surface_names = faces.surface_names;
  mesh.surface_specular = faces.surface_specular;
  mesh.scale = faces.scale;
  struct Key {
    std::int32_t surface;
    double x, y, z;
    bool operator==(const Key& o) const {
      return surface == o.surface && std::memcmp(&x, &o.x, 3 * sizeof(double)) == 0;
    }
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t b[3];
      std::memcpy(b, &k.x, sizeof b);
      return hash_keys(static_cast<std::uint64_t>(k.surface), b[0] ^ mix64(b[1]), b[2]);
    }
  };
  std::unordered_map<Key, std::int32_t, KeyHash> index;
  std::vector<std::int32_t> leaves, stack;
  for (std::int32_t f = 0; f < faces.size(); ++f) {
    stack.assign(1, f);
    while (!stack.empty()) {
      const std::int32_t i = stack.back();
      stack.pop_back();
      if (h.is_leaf(i)) {
        leaves.push_back(i);
        continue;
      }
      for (int k = h.node(i).child_count - 1; k >= 0; --k) stack.push_back(h.child(i, k));
    }
  }
  mesh.patches.reserve(leaves.size());
  out.B.resize(static_cast<Eigen::Index>(leaves.size()), 3);
  out.error_bound.resize(static_cast<Eigen::Index>(leaves.size()));
  for (std::size_t l = 0; l < leaves.size(); ++l) {
    const std::int32_t i = leaves[l];
    const ff::PatchGeom& g = h.geom(i);
    const Patch& face = faces.patches[h.node(i).face];
    Patch p = face;
    p.vertex_count = g.n;
    p.area = g.area;
    p.centroid = g.centroid;
    for (int c = 0; c < g.n; ++c) {
      const Key key{face.surface, g.p[c].x(), g.p[c].y(), g.p[c].z()};
      auto [it, inserted] = index.emplace(key, static_cast<std::int32_t>(mesh.vertices.size()));
      if (inserted) {
        mesh.vertices.push_back(g.p[c]);
        mesh.vertex_surface.push_back(face.surface);
      }
      p.vertices[c] = it->second;
    }
    mesh.patches.push_back(p);
    out.B.row(static_cast<Eigen::Index>(l)) = s.B[i].transpose();
    out.error_bound[static_cast<Eigen::Index>(l)] = face.rho.maxCoeff() * error[i];
  }
}

/// Per node, the transfer error (W/m^2, max channel) gathered over its own links and, at the
/// leaves, over their ancestors' too (pushed down uniformly).
std::vector<double> leaf_irradiance_error(const Hierarchy& h, const LinkTable& t,
                                          const hr::LinkContext& ctx, const State& s, int threads) {
  std::vector<double> e(h.nodes().size(), 0.0);
  const std::int64_t runs = static_cast<std::int64_t>(t.starts.size()) - 1;
  parallel_for(runs, kGatherChunk, threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t r = begin; r < end; ++r) {  // receiver p's links, in link order
      const std::int32_t p = t.links[t.starts[r]].p;
      for (std::int64_t k = t.starts[r]; k < t.starts[r + 1]; ++k) {
        const Link& l = t.links[k];
        e[p] += hr::link_error(ctx, l, s.source(l.q)) / h.node(p).area;
      }
    }
  });
  std::vector<std::pair<std::int32_t, double>> stack{{h.root(), 0.0}};
  while (!stack.empty()) {
    const auto [i, down] = stack.back();
    stack.pop_back();
    e[i] += down;
    for (int k = 0; k < h.node(i).child_count; ++k) stack.emplace_back(h.child(i, k), e[i]);
  }
  return e;
}

/// Power bookkeeping over the leaves (header of HierarchicalEnergy).
void energy_balance(const Hierarchy& h, const State& s, HierarchicalStats& st) {
  for (int c = 0; c < 3; ++c) st.energy[c] = HierarchicalEnergy{};
  double sent[3] = {0, 0, 0}, received[3] = {0, 0, 0};
  for (std::int32_t i = 0; i < h.size(); ++i) {
    if (!h.is_leaf(i) || h.node(i).cluster) continue;
    const Patch& face = h.faces().patches[h.node(i).face];
    const double a = h.node(i).area;
    for (int c = 0; c < 3; ++c) {
      st.energy[c].emitted += a * face.emission[c];
      st.energy[c].absorbed += a * (1.0 - face.rho[c]) * s.H[i][c];
      sent[c] += a * s.B[i][c];
      received[c] += a * s.H[i][c];
    }
  }
  for (int c = 0; c < 3; ++c) {
    HierarchicalEnergy& e = st.energy[c];
    e.escaped = sent[c] - received[c];
    e.relative_imbalance =
        e.emitted > 0 ? std::abs(e.emitted - e.absorbed - e.escaped) / e.emitted : 0.0;
  }
}

/// Emitting surfaces whose faces can exchange light with no other face (HierarchicalStats).
std::vector<std::int32_t> blind_emitters(const Hierarchy& h, double plane_eps) {
  const PatchMesh& faces = h.faces();
  std::vector<std::int32_t> emitting;
  for (std::int32_t f = 0; f < faces.size(); ++f)
    if (faces.patches[f].emission.maxCoeff() > 0.0) emitting.push_back(f);
  if (static_cast<double>(emitting.size()) * faces.size() > kBlindCheckPairs) return {};
  std::vector<char> sees(faces.surface_names.size(), 0), emits(sees.size(), 0);
  for (const std::int32_t f : emitting) {
    const std::int32_t s = faces.patches[f].surface;
    emits[s] = 1;
    for (std::int32_t g = 0; g < faces.size() && !sees[s]; ++g)
      if (g != f && ff::can_exchange(h.geom(f), h.geom(g), plane_eps)) sees[s] = 1;
  }
  std::vector<std::int32_t> out;
  for (std::size_t s = 0; s < sees.size(); ++s)
    if (emits[s] && !sees[s]) out.push_back(static_cast<std::int32_t>(s));
  return out;
}

}  // namespace

HierarchicalResult solve_hierarchical(const Scene& scene, const HierarchicalOptions& o) {
  check_options(o);
  for (const Surface& s : scene.surfaces)
    if (scene.materials[s.material].specular.any())
      throw UsageError("--method hierarchical handles diffuse surfaces only, and surface '" +
                       s.name + "' is specular (a mirror or glass): use --method matrix, whose "
                       "extended form factors follow rays through it");
  const int threads = resolve_threads(o.threads);
  HierarchicalResult result;
  HierarchicalStats& st = result.stats;
  Timer timer;
  Hierarchy h(mesh_scene(scene, MeshOptions{}));
  const Bvh bvh(h.faces(), threads);
  st.faces = h.faces().size();
  st.clusters = h.clusters();
  st.blind_emitters = blind_emitters(h, ff::kPlaneEps * h.faces().scale);
  st.build_seconds = timer.seconds();

  double total_area = 0.0;
  Eigen::Vector3d emitted = Eigen::Vector3d::Zero();
  for (const Patch& f : h.faces().patches) {
    total_area += f.area;
    emitted += f.area * f.emission;
  }
  st.min_area = o.min_area > 0 ? o.min_area : kAutoMinAreaFraction * total_area;
  const double scale = h.faces().scale;
  const hr::LinkContext ctx{h,
                            bvh,
                            o.link_rays,
                            o.seed,
                            ff::kRayOffset * scale,
                            ff::kPlaneEps * scale,
                            st.min_area,
                            o.epsilon * emitted.maxCoeff()};

  State s;
  s.resize(h.nodes().size());
  push_pull(h, h.root(), kNoField, s);  // B = E

  LinkTable table;
  const Budget budget{h, table, s, o.memory_limit};
  std::vector<std::int32_t> to_split;
  std::vector<std::pair<std::int32_t, std::int32_t>> pending;
  if (emitted.maxCoeff() > 0.0) pending.emplace_back(h.root(), h.root());
  Progress progress("hierarchical", o.progress ? o.max_passes : 0, "links");
  std::int64_t rays = 0;
  for (int pass = 1; pass <= o.max_passes; ++pass) {
    Timer refine_timer;
    std::vector<Refinement> refine;
    // The spare table array (and the headroom of a new one) saves page faults, not memory:
    // given up once the hierarchy holds half the limit.
    const bool tight = budget.limit > 0 && budget.held() > 0.5 * budget.limit;
    if (tight) LinkArray().swap(table.spare);
    if (pass > 1) {  // recheck the accepted links against the new B
      // The verdicts, and at worst every link to refine.
      budget.check(static_cast<double>(table.links.size()) * (1.0 + sizeof(Refinement)), "recheck");
      std::vector<Action> verdict(table.links.size());
      parallel_for(static_cast<std::int64_t>(verdict.size()), kGatherChunk, threads,
                   [&](std::int64_t b, std::int64_t e) {
                     for (std::int64_t k = b; k < e; ++k)
                       verdict[k] = hr::recheck_link(ctx, table.links[k],
                                                     s.source(table.links[k].q));
                   });
      std::size_t kept = 0;
      for (std::size_t k = 0; k < verdict.size(); ++k) {
        if (verdict[k] == Action::Accept)
          table.links[kept++] = table.links[k];
        else
          refine.push_back({table.links[k].p, table.links[k].q, verdict[k]});
      }
      table.links.resize(kept);
      if (refine.empty()) break;  // nothing changes: the previous pass's solution stands
    }
    ++st.passes;
    while (!pending.empty() || !refine.empty()) {
      std::size_t new_links = 0;
      {  // the wave's peak: new nodes (a reallocation holds old and new buffers), its links
         // (pending, evaluated, actions, at worst all refined again); the links accepted in
         // earlier waves are held (Budget::held) until the pass's index
        std::size_t new_nodes = 0;
        std::tie(new_nodes, new_links) = wave_size(h, refine, to_split);
        const std::size_t nodes = h.nodes().size();
        const std::size_t node_cap = Budget::grown(nodes, h.nodes().capacity(), new_nodes);
        const std::size_t wave = pending.size() + new_links;
        double extra = static_cast<double>(to_split.capacity()) * sizeof(std::int32_t) +
                       static_cast<double>(wave) * (2 * sizeof(pending[0]) + sizeof(Link) +
                                                    sizeof(Action) + sizeof(Refinement));
        if (node_cap > h.nodes().capacity())
          extra += static_cast<double>(node_cap) *
                   (sizeof(hr::Node) + sizeof(ff::PatchGeom) + State::kBytesPerNode);
        budget.check(extra, "next refinement wave");
        if (node_cap > h.nodes().capacity()) {
          h.reserve(node_cap);
          s.reserve(node_cap);
        }
      }
      split_nodes(h, to_split, s);
      auto children = expand(h, refine, new_links);
      if (pending.empty())
        pending.swap(children);
      else
        pending.insert(pending.end(), children.begin(), children.end());
      std::vector<std::pair<std::int32_t, std::int32_t>>().swap(children);
      refine.clear();
      LinkArray evaluated(pending.size());
      std::vector<Action> action(pending.size());
      std::vector<std::int64_t> chunk_rays((pending.size() + kEvalChunk - 1) / kEvalChunk, 0);
      parallel_for(static_cast<std::int64_t>(pending.size()), kEvalChunk, threads,
                   [&](std::int64_t b, std::int64_t e) {
                     std::int64_t r = 0;
                     for (std::int64_t k = b; k < e; ++k) {
                       const auto [p, q] = pending[k];
                       Link link;
                       action[k] = hr::evaluate_link(ctx, p, q, s.source(q), link, r);
                       evaluated[k] = link;
                     }
                     chunk_rays[b / kEvalChunk] += r;
                   });
      for (const std::int64_t r : chunk_rays) rays += r;
      refine.reserve(
          static_cast<std::size_t>(std::count_if(action.begin(), action.end(), [](Action a) {
            return a != Action::Accept && a != Action::Drop;
          })));
      std::size_t accepted = 0;  // moved to the front of `evaluated`, in order
      for (std::size_t k = 0; k < pending.size(); ++k) {
        if (action[k] == Action::Accept)
          evaluated[accepted++] = evaluated[k];
        else if (action[k] != Action::Drop)
          refine.push_back({pending[k].first, pending[k].second, action[k]});
      }
      evaluated.resize(accepted);
      // Kept until the pass's index: not at twice the size it needs.
      if (accepted < evaluated.capacity() / 2) evaluated.shrink_to_fit();
      if (accepted > 0) table.fresh.push_back(std::move(evaluated));
      std::vector<std::pair<std::int32_t, std::int32_t>>().swap(pending);
    }
    budget.check(table.index_bytes(tight), "link index");
    table.index(threads, tight);
    st.refine_seconds += refine_timer.seconds();

    Timer solve_timer;
    s.resize(h.nodes().size());
    ParallelPushPull sweep_tree(h, threads);
    st.converged = false;
    for (int it = 1; it <= o.max_iterations; ++it) {
      gather(h, table, s, threads);
      const Sweep sweep = sweep_tree(s);
      ++st.iterations;
      st.change = sweep.max_b > 0 ? sweep.change / sweep.max_b : 0.0;
      if (st.change <= o.tol) {
        st.converged = true;
        break;
      }
    }
    st.solve_seconds += solve_timer.seconds();
    progress.advance(1, static_cast<std::int64_t>(table.links.size()));
  }
  progress.finish();
  LinkArray().swap(table.spare);
  if (emitted.maxCoeff() <= 0.0) st.converged = true;  // B = E = 0 is exact

  st.elements = h.size() - h.clusters();
  st.links = static_cast<std::int64_t>(table.links.size());
  for (const Link& l : table.links)
    st.cluster_links += h.node(l.p).cluster || h.node(l.q).cluster;
  st.rays = rays;
  st.memory_bytes = budget.held();
  energy_balance(h, s, st);
  export_leaves(h, s, leaf_irradiance_error(h, table, ctx, s, threads), result);
  st.leaves = result.mesh.size();
  return result;
}

}  // namespace lambert
