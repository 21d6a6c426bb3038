// Error bars that mean what they say: over many occluded and unoccluded configurations,
// near and far, equal and unequal sizes, and seeds, the exact factor lies within ± 2
// stderr of the estimate in at least 95 % of cases, and the reported stderr matches the
// spread of the estimates over seeds within a factor of 1.5 (issue: mc's was 3-11 x).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/analytic.hpp"
#include "geometry/formfactors/formfactors.hpp"

namespace lambert {
namespace {

const Material kGrey{"m", Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Zero()};

// Emitter a = [0, wa] x [0, wa] at z = 0 (up), receiver b = [ox, ox + wb] x [0, wb] at
// z = h (down). A plate 1e-3 off one of them (just in front of b, or just above a; 100 x
// the ray offset, 1e-6 of the scene's diagonal) hides its part x > cut; the exact G is
// then the closed form of the unhidden rectangle (the plate's penumbra on the hidden
// patch is < 1e-3 / h wide: ~1e-3 relative, < 1/20 of the smallest stderr tested).
struct Config {
  double wa, wb, h, ox, cut;
  bool near_receiver;  // plate in front of b (else just above a); cut < 0: no plate
};

Scene scene_of(const Config& c) {
  Scene s;
  add_polygon(s, "a", kGrey, {{0, 0, 0}, {c.wa, 0, 0}, {c.wa, c.wa, 0}, {0, c.wa, 0}});
  add_polygon(s, "b", kGrey,
              {{c.ox, 0, c.h}, {c.ox, c.wb, c.h}, {c.ox + c.wb, c.wb, c.h}, {c.ox + c.wb, 0, c.h}});
  if (c.cut >= 0.0) {
    const double z = c.near_receiver ? c.h - 1e-3 : 1e-3, far = 3.0;
    add_polygon(s, "plate", kGrey, {{c.cut, -far, z}, {far, -far, z}, {far, far, z}, {c.cut, far, z}});
  }
  return s;
}

double exact_G(const Config& c) {
  double ax1 = c.wa, bx0 = c.ox, bx1 = c.ox + c.wb;
  if (c.cut >= 0.0 && c.near_receiver) bx1 = std::min(bx1, c.cut);
  if (c.cut >= 0.0 && !c.near_receiver) ax1 = std::min(ax1, c.cut);
  if (bx1 <= bx0 || ax1 <= 0.0) return 0.0;
  return parallel_rectangles_G(0, ax1, 0, c.wa, bx0, bx1, 0, c.wb, c.h);
}

std::vector<Config> configs() {
  std::vector<Config> out;
  for (double h : {0.3, 1.0, 3.0})                                      // near .. far
    for (auto [wa, wb] : {std::pair{1.0, 1.0}, {0.2, 1.0}, {1.0, 0.2}})  // sizes 1:1, 1:5, 5:1
      for (bool near_receiver : {true, false}) {
        const double w = near_receiver ? wb : wa, x0 = near_receiver ? 0.1 : 0.0;
        out.push_back({wa, wb, h, x0, x0 + 0.5 * w, near_receiver});   // half hidden
        out.push_back({wa, wb, h, x0, x0 + 0.2 * w, near_receiver});   // mostly hidden
      }
  out.push_back({1.0, 1.0, 1.0, 0.0, -1.0, true});  // unoccluded
  out.push_back({0.2, 1.0, 0.3, 0.4, -1.0, true});
  return out;
}

void calibrate(const std::string& estimator, int samples) {
  constexpr int kSeeds = 12;
  int inside = 0, total = 0;
  std::uint64_t stream = 0;
  double rel_reported2 = 0.0, rel_spread2 = 0.0;
  for (const Config& c : configs()) {
    const PatchMesh mesh = mesh_scene(scene_of(c), {});
    const double exact = exact_G(c);
    std::vector<double> est;
    double var_sum = 0.0;
    for (int seed = 1; seed <= kSeeds; ++seed) {
      FormFactorOptions o;
      o.estimator = estimator;
      o.pair.samples = samples;
      // A fresh seed per case: the same seed in every configuration would reuse the same
      // random shifts (streams hash the seed with the patch indices, 0 and 1 in every
      // scene), making the cases' misses correlated.
      o.run.seed = 1000 * ++stream + seed;
      o.run.with_stderr = true;
      o.run.progress = false;
      const FormFactors ff = compute_form_factors(mesh, o);
      const double G = ff.F.coeff(0, 1) * mesh.patches[0].area;
      const double se = ff.stderr_F.coeff(0, 1) * mesh.patches[0].area;
      inside += std::abs(G - exact) <= 2.0 * se;
      ++total;
      est.push_back(G);
      var_sum += se * se;
    }
    double mean = 0.0, s2 = 0.0;
    for (double g : est) mean += g / kSeeds;
    for (double g : est) s2 += (g - mean) * (g - mean) / (kSeeds - 1);
    const double spread = std::sqrt(s2), reported = std::sqrt(var_sum / kSeeds);
    // Unoccluded hybrid pairs have no sampling error (spread 0): skipped.
    if (spread > 1e-6 * exact) {
      // One configuration: the spread over 12 seeds of a few-ray estimate is itself
      // uncertain by ~1/sqrt(2 * 11) = 21 % for normal errors and more for the skewed
      // ones (measured over 200 seeds, every configuration here has a ratio of 1.15-1.3):
      // a gross check only, [1/4, 4].
      EXPECT_GT(reported / spread, 0.25) << estimator << " h " << c.h << " cut " << c.cut;
      EXPECT_LT(reported / spread, 4.0) << estimator << " h " << c.h << " cut " << c.cut;
      rel_reported2 += reported * reported / (exact * exact);
      rel_spread2 += s2 / (exact * exact);
    }
  }
  // Pooled over the ~36 occluded configurations (each a relative spread), the ratio is
  // known to ~1/sqrt(2 * 36 * 11) = 3.6 %: within a factor of 1.5 as the issue asks.
  const double pooled = std::sqrt(rel_reported2 / rel_spread2);
  EXPECT_GT(pooled, 1.0 / 1.5) << estimator;
  EXPECT_LT(pooled, 1.5) << estimator;
  // >= 95 % within 2 stderr; the stderr is scaled for 97 % (replicates.hpp), and with
  // 456 cases the binomial spread of the observed coverage is 0.8 %: 95 % is 2.5σ below.
  EXPECT_GE(inside, 0.95 * total) << estimator << ": " << inside << " of " << total;
  std::printf("%s: %d of %d (%.1f %%) within 2 stderr; reported / spread %.2f\n",
              estimator.c_str(), inside, total, 100.0 * inside / total, pooled);
}

}  // namespace

TEST(ErrorBarsSlow, HybridCoverageAndSpreadAreCalibrated) { calibrate("hybrid", 64); }
TEST(ErrorBarsSlow, McCoverageAndSpreadAreCalibrated) { calibrate("mc", 256); }

// A tapered receiver (width 2 -> 0.1) with its narrow half hidden: sampling a bilinear
// quad uniformly in (u, v) without its Jacobian weighted the visible fraction by the
// parametrisation (10-15 % low). The exact G is the unoccluded G to the wide half, which
// hybrid's quadrature gives to 1e-6 (quadrature_test.cpp).
TEST(ErrorBars, TaperedHalfShadedReceiverIsWithinThreeSigma) {
  Scene open, shaded;
  add_polygon(open, "a", kGrey, {{-1, 0, 0}, {1, 0, 0}, {1, 2, 0}, {-1, 2, 0}});
  add_polygon(open, "wide", kGrey, {{-1, 0, 1}, {-0.525, 1, 1}, {0.525, 1, 1}, {1, 0, 1}});
  add_polygon(shaded, "a", kGrey, {{-1, 0, 0}, {1, 0, 0}, {1, 2, 0}, {-1, 2, 0}});
  add_polygon(shaded, "b", kGrey, {{-1, 0, 1}, {-0.05, 2, 1}, {0.05, 2, 1}, {1, 0, 1}});
  add_polygon(shaded, "plate", kGrey, {{-3, 1, 1 - 1e-4}, {3, 1, 1 - 1e-4}, {3, 4, 1 - 1e-4}, {-3, 4, 1 - 1e-4}});
  FormFactorOptions o;
  o.pair.samples = 4;
  o.run.progress = false;
  const PatchMesh open_mesh = mesh_scene(open, {});
  const double exact = compute_form_factors(open_mesh, o).F.coeff(0, 1) * open_mesh.patches[0].area;
  const PatchMesh mesh = mesh_scene(shaded, {});
  ASSERT_EQ(mesh.patches[1].vertex_count, 4);  // one non-parallelogram quad
  for (const std::string est : {"hybrid", "mc"}) {
    o.estimator = est;
    o.pair.samples = 1 << 14;
    o.run.with_stderr = true;
    const FormFactors ff = compute_form_factors(mesh, o);
    const double G = ff.F.coeff(0, 1) * mesh.patches[0].area;
    const double se = ff.stderr_F.coeff(0, 1) * mesh.patches[0].area;
    // 3 stderr (two-sided false alarm < 0.3 %) plus the plate's penumbra: it is 1e-4 in
    // front of b (14 x the ray offset), so its shadow edge on b moves by <= 1e-4 x
    // (Δy / Δz <= 2) = 2e-4, in the band of highest kernel; measured with the plate 1e-3
    // off, both estimators were 2.4e-3 low, so 1e-4 off gives ~2.4e-4: 5e-4 allowed.
    EXPECT_NEAR(G, exact, 3 * se + 5e-4 * exact) << est << " se " << se;
  }
}

// CAD slivers (issue 36): two strips 100 mm x 0.1 mm, 30 mm apart, each as the two needle
// triangles an exporter writes, with a plate just in front of the upper one hiding its part
// x > 50 mm. Along a sliver hybrid draws (x, y) jointly by rejection against a bound of K
// from the cell's long axis (cell_distance_bound); a bound that K exceeded anywhere would
// bias the visible fraction. The exact G is the rectangles' closed form of the unhidden
// half. 3 stderr (two-sided false alarm < 0.3 %) plus the plate's penumbra: 1e-5 in front
// of b (100 x the ray offset of 1e-6 x the 0.1 diagonal), so its shadow edge moves by
// <= 1e-5 x (Δx / Δz <= 0.1 / 0.03) = 3.3e-5 along b, a band carrying <= its share of the
// visible 50 mm times the kernel's peak over its mean along b (< 2 at 30 mm from a 100 mm
// strip): 3.3e-5 / 0.05 x 2 = 1.3e-3 of G.
TEST(ErrorBars, HalfHiddenSliverStripsAreWithinThreeSigma) {
  const double L = 0.1, w = 1e-4, h = 0.03, cut = 0.05, z = h - 1e-5;
  Scene s;
  add_polygon(s, "a", kGrey, {{0, 0, 0}, {L, 0, 0}, {L, w, 0}});
  add_polygon(s, "a", kGrey, {{0, 0, 0}, {L, w, 0}, {0, w, 0}});
  add_polygon(s, "b", kGrey, {{0, 0, h}, {L, w, h}, {L, 0, h}});
  add_polygon(s, "b", kGrey, {{0, 0, h}, {0, w, h}, {L, w, h}});
  add_polygon(s, "plate", kGrey, {{cut, -1, z}, {1, -1, z}, {1, 1, z}, {cut, 1, z}});
  const PatchMesh mesh = mesh_scene(s, {});
  ASSERT_EQ(mesh.size(), 5);
  FormFactorOptions o;
  o.estimator = "hybrid";
  o.pair.samples = 1 << 14;
  o.run.with_stderr = true;
  o.run.progress = false;
  const FormFactors ff = compute_form_factors(mesh, o);
  double G = 0.0, var = 0.0;
  for (std::int32_t i : {0, 1})
    for (std::int32_t j : {2, 3}) {
      const double A = mesh.patches[i].area, se = ff.stderr_F.coeff(i, j) * A;
      G += ff.F.coeff(i, j) * A;
      var += se * se;  // the pairs' streams are independent
    }
  const double exact = parallel_rectangles_G(0, L, 0, w, 0, cut, 0, w, h);
  EXPECT_NEAR(G, exact, 3 * std::sqrt(var) + 1.3e-3 * exact) << "se " << std::sqrt(var);
  std::printf("G %.6e exact %.6e: %.2f stderr\n", G, exact, (G - exact) / std::sqrt(var));
}

}  // namespace lambert

namespace lambert {
namespace {

// Quads of a surface of revolution r(t), z(t) for t in [0, 1], `seg` around and `rings`
// along, wound so that their normals point outward (out = true) or inward.
void add_revolved(Scene& s, const std::string& name, int seg, int rings, bool out,
                  double (*r)(double), double (*z)(double), const Eigen::Vector3d& at) {
  for (int k = 0; k < rings; ++k)
    for (int i = 0; i < seg; ++i) {
      const double a0 = 2 * M_PI * i / seg, a1 = 2 * M_PI * (i + 1) / seg;
      const double t0 = double(k) / rings, t1 = double(k + 1) / rings;
      auto p = [&](double a, double t) {
        return Eigen::Vector3d(at.x() + r(t) * std::cos(a), at.y() + r(t) * std::sin(a), at.z() + z(t));
      };
      std::vector<Eigen::Vector3d> q = {p(a0, t0), p(a1, t0), p(a1, t1), p(a0, t1)};
      if (r(t0) == 0.0) q.erase(q.begin() + 1);       // pole: a triangle
      else if (r(t1) == 0.0) q.erase(q.begin() + 2);
      if (!out) std::reverse(q.begin(), q.end());
      add_polygon(s, name, kGrey, q);
    }
}
double sphere_r(double t) { return t <= 0.0 || t >= 1.0 ? 0.0 : 3.0 * std::sin(M_PI * t); }
double sphere_z(double t) { return -3.0 * std::cos(M_PI * t); }
// A closed cylinder of radius 0.4 and height 2 centred on its axis (caps as flat rings).
double cyl_r(double t) { return t <= 0.0 || t >= 1.0 ? 0.0 : 0.4; }
double cyl_z(double t) { return t <= 1.0 / 3 ? -1.0 : t >= 2.0 / 3 ? 1.0 : 6.0 * (t - 0.5); }

}  // namespace

// A cylinder radiating to an enclosing (16-segment) sphere past a blocking cylinder: the
// enclosure is closed and the cylinder convex, so every row of the cylinder sums to 1
// exactly. Large, partly hidden sphere patches are where a kernel-weighted ratio of few
// rays was biased (+1.67 % with 16 segments); an unbiased visible fraction keeps every row
// at 1 within its own error.
TEST(ErrorBarsSlow, EnclosedCylinderPastABlockerHasRowSumsOfOne) {
  Scene s;
  add_revolved(s, "sphere", 16, 8, false, sphere_r, sphere_z, {0, 0, 0});
  add_revolved(s, "emitter", 8, 3, true, cyl_r, cyl_z, {-1.2, 0, 0});
  add_revolved(s, "blocker", 8, 3, true, cyl_r, cyl_z, {0.2, 0, 0});
  const PatchMesh mesh = mesh_scene(s, {});
  FormFactorOptions o;
  o.pair.samples = 64;
  o.run.with_stderr = true;
  o.run.progress = false;
  for (const std::string est : {"hybrid", "mc"}) {
    o.estimator = est;
    const FormFactors ff = compute_form_factors(mesh, o);
    double total = 0.0, total_var = 0.0, area = 0.0;
    for (std::int32_t i = 0; i < mesh.size(); ++i) {
      if (mesh.surface_names[mesh.patches[i].surface] != "emitter") continue;
      double sum = 0.0, var = 0.0;
      for (SparseF::InnerIterator it(ff.F, i), st(ff.stderr_F, i); it; ++it, ++st) {
        sum += it.value();
        var += st.value() * st.value();
      }
      // 4 stderr per row (two-sided false alarm 6e-5 over 40 rows for normal errors).
      EXPECT_NEAR(sum, 1.0, 4 * std::sqrt(var)) << est << " row " << i;
      total += mesh.patches[i].area * sum;
      total_var += mesh.patches[i].area * mesh.patches[i].area * var;
      area += mesh.patches[i].area;
    }
    // The area-weighted mean row sum: the bias test (errors of rows are independent).
    EXPECT_NEAR(total / area, 1.0, 4 * std::sqrt(total_var) / area) << est;
    std::printf("%s: mean row sum %.5f +- %.5f\n", est.c_str(), total / area, std::sqrt(total_var) / area);
  }
}

}  // namespace lambert
