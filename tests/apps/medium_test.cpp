// Participating media: the zonal method's physics (geometry/formfactors/media.hpp) solved
// through pipeline/problem.hpp's extended problem, and the CLI's medium options.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "apps/cli.hpp"
#include "common/run_cli.hpp"
#include "common/temp_dir.hpp"
#include "geometry/analytic.hpp"
#include "geometry/formfactors/media.hpp"
#include "geometry/visibility/bvh.hpp"
#include "pipeline/problem.hpp"

namespace lambert {
namespace {

void add_quad(Scene& s, const std::string& name, std::array<Eigen::Vector3d, 4> corners) {
  const auto first = static_cast<std::int32_t>(s.vertices.size());
  for (const auto& c : corners) s.vertices.push_back(c);
  s.materials.push_back({name, Eigen::Vector3d::Zero()});
  s.surfaces.push_back({name, static_cast<std::int32_t>(s.materials.size() - 1)});
  Face f;
  f.vertices = {first, first + 1, first + 2, first + 3};
  f.surface = static_cast<std::int32_t>(s.surfaces.size() - 1);
  s.faces.push_back(f);
}

// Two directly opposed parallel squares of side w at distance d: "a" in z = 0 facing +z,
// "b" in z = d facing -z.
Scene opposed_squares(double w, double d) {
  Scene s;
  add_quad(s, "a", {{{0, 0, 0}, {w, 0, 0}, {w, w, 0}, {0, w, 0}}});
  add_quad(s, "b", {{{0, 0, d}, {0, w, d}, {w, w, d}, {w, 0, d}}});
  return s;
}

FormFactors surface_factors(const PatchMesh& mesh, const std::string& estimator) {
  FormFactorOptions o;
  o.estimator = estimator;
  o.pair.samples = 64;
  o.analytic.tol = 1e-7;
  o.run.progress = false;
  return compute_form_factors(mesh, o);
}

FormFactors extended_factors(const PatchMesh& mesh, const Medium& medium, const Zones& zones,
                             const FormFactors& surface, std::uint64_t seed, int rays = 512,
                             int samples = 64) {
  MediumFactorOptions o;
  o.rays = rays;
  o.transmittance_samples = samples;
  o.seed = seed;
  const Bvh bvh(mesh);
  return extend_with_medium(mesh, medium, zones, surface, o, bvh);
}

RadiositySolution solve_direct(const RadiosityProblem& p) {
  SolveOptions so;
  so.solver = "direct";
  return solve_radiosity(p, so);
}

// Uniform radiosity b everywhere is the exact solution when every row of F sums to 1 and
// E_i = (1 - rho_i) b. With the row sums s_i of the estimated F, B - b solves
// K (B - b) = r with r_i = rho_i b (s_i - 1); K^-1 >= 0 (an M-matrix), so
// ||B - b||_inf <= ||K^-1 1||_inf ||r||_inf, where K^-1 1 is one more direct solve. The
// direct solve itself is exact to ~1e-12 relative (a few hundred unknowns, condition
// ~1/(1 - rho_eff) ~ 10): 1e-9 b covers it. Returns max |B - b| / b for the report.
double expect_uniform(const RadiosityProblem& p, double b) {
  const RadiositySolution s = solve_direct(p);
  const Eigen::VectorXd rows = p.F->row_sums();
  RadiosityProblem unit = p;
  unit.emission.setOnes();
  const double amplification = solve_direct(unit).B.cwiseAbs().maxCoeff();
  double worst = 0.0;
  for (int c = 0; c < 3; ++c) {
    const double r = (p.rho.col(c).array() * b * (rows.array() - 1.0)).abs().maxCoeff();
    const double bound = amplification * r + 1e-9 * b;
    const double err = (s.B.col(c).array() - b).abs().maxCoeff();
    EXPECT_LE(err, bound) << "channel " << c << " amplification " << amplification
                          << " max row-sum deviation " << (rows.array() - 1.0).abs().maxCoeff();
    worst = std::max(worst, err / b);
  }
  return worst;
}

// The unit cube's inside meshed at max_edge, every wall with reflectance rho and emission E,
// filled with a homogeneous medium of `voxels`^3 zones.
struct CubeCase {
  PatchMesh mesh;
  Medium medium;
  Zones zones;
  FormFactors F;
  RadiosityProblem problem;
};

void build_cube(CubeCase& c, double rho, double E, const Eigen::Vector3d& sa,
                const Eigen::Vector3d& ss, const Eigen::Vector3d& e, int voxels) {
  c.mesh = mesh_scene(unit_cube(), {0.25, 0});
  for (Patch& p : c.mesh.patches) {
    p.rho.setConstant(rho);
    p.emission.setConstant(E);
  }
  c.medium = homogeneous_medium({0, 0, 0}, {1, 1, 1}, Eigen::Vector3i::Constant(voxels), sa, ss, e);
  c.zones = make_zones(c.medium);
  // "analytic": exact contour factors to 1e-7 per entry, so the walls' row sums are 1 to
  // ~1e-5 and the test sees the medium's part.
  c.F = extended_factors(c.mesh, c.medium, c.zones, surface_factors(c.mesh, "analytic"), 3);
  c.problem = make_extended_problem(c.mesh, c.F.F, c.zones.albedo, c.zones.emission, c.zones.area);
}

// E3(t) = ∫_0^1 mu exp(-t/mu) dmu, and the same from 0 to m, by composite Simpson on 4000
// intervals: the integrand is smooth (all derivatives vanish at 0), error ~1e-14.
double e3_partial(double t, double m) {
  const int n = 4000;
  const double h = m / n;
  auto f = [t](double mu) { return mu > 0 ? mu * std::exp(-t / mu) : 0.0; };
  double s = f(0) + f(m);
  for (int k = 1; k < n; ++k) s += (k % 2 ? 4 : 2) * f(k * h);
  return s * h / 3;
}

}  // namespace

TEST(MediumFactors, SmallParallelPatchesAreAttenuatedByExpSigmaD) {
  // Squares of side 0.1 at d = 1 in a medium with sigma_t = 0.8 (absorbing 0.5, scattering 0.3).
  const double w = 0.1, d = 1.0, st = 0.8;
  const PatchMesh mesh = mesh_scene(opposed_squares(w, d), {0.0, 0});
  const Medium medium =
      homogeneous_medium({-1, -1, -0.5}, {2, 2, 1.5}, {6, 6, 4}, Eigen::Vector3d::Constant(0.5),
                         Eigen::Vector3d::Constant(0.3), Eigen::Vector3d::Zero());
  // Size effect: every point pair is between d and r_max = sqrt(d² + 2 w²) apart, so the
  // kernel-weighted mean transmittance lies in [exp(-st r_max), exp(-st d)] (8e-3 relative).
  const double t_hi = std::exp(-st * d), t_lo = std::exp(-st * std::sqrt(d * d + 2 * w * w));
  const double t = pair_transmittance(mesh, medium, 0, 1, 256, 11);
  EXPECT_GE(t, t_lo);
  EXPECT_LE(t, t_hi);
  EXPECT_EQ(t, pair_transmittance(mesh, medium, 1, 0, 256, 11));  // symmetric bit for bit

  // Through the whole extension: F_01 = F_01(estimator) x T exactly (patch rows are never
  // rescaled, media.hpp), so within the size effect of exp(-st d) times the estimator's
  // factor; the exact unattenuated factor (Howell C-11) checks that factor.
  const Zones zones = make_zones(medium);
  FormFactors surface = surface_factors(mesh, "analytic");
  const double f0 = parallel_rectangles_factor(w, w, d);
  ASSERT_NEAR(surface.F.coeff(0, 1), f0, 1e-6);  // analytic to its 1e-7 target, margin 10
  const FormFactors ext = extended_factors(mesh, medium, zones, surface, 5);
  const double f = ext.F.coeff(0, 1);
  std::printf("F01 %.6g, unattenuated x exp(-st d) %.6g (ratio %.5f; size effect >= %.5f)\n", f,
              f0 * t_hi, f / (f0 * t_hi), t_lo / t_hi);
  // Rounding of one product: 1e-15 absolute on factors ~1e-3.
  EXPECT_GE(f, surface.F.coeff(0, 1) * t_lo - 1e-15);
  EXPECT_LE(f, surface.F.coeff(0, 1) * t_hi + 1e-15);
  // Reciprocity by construction: A_0 F_01 = A_1 F_10 to rounding (equal areas).
  EXPECT_NEAR(ext.F.coeff(0, 1), ext.F.coeff(1, 0), 1e-15);
}

TEST(MediumFactors, BitwiseIdenticalForAnyThreadCount) {
  const PatchMesh mesh = mesh_scene(unit_cube(), {0.5, 0});
  const Medium medium =
      homogeneous_medium({0.1, 0, 0}, {1, 0.8, 1}, {3, 2, 4}, Eigen::Vector3d(0.3, 0.5, 0.7),
                         Eigen::Vector3d(0.7, 0.5, 0.3), Eigen::Vector3d::Zero());
  const Zones zones = make_zones(medium);
  const FormFactors surface = surface_factors(mesh, "hybrid");
  const Bvh bvh(mesh);
  MediumFactorOptions o;
  o.rays = 64;
  o.transmittance_samples = 8;
  o.threads = 1;
  const FormFactors one = extend_with_medium(mesh, medium, zones, surface, o, bvh);
  o.threads = 2;
  const FormFactors two = extend_with_medium(mesh, medium, zones, surface, o, bvh);
  ASSERT_EQ(one.F.nonZeros(), two.F.nonZeros());
  for (std::int64_t k = 0; k < one.F.nonZeros(); ++k) {
    ASSERT_EQ(one.F.innerIndexPtr()[k], two.F.innerIndexPtr()[k]);
    ASSERT_EQ(one.F.valuePtr()[k], two.F.valuePtr()[k]);
  }
  // Reciprocity by construction over every block: A_i F_ij = A_j F_ji to rounding.
  std::vector<double> area(mesh.patches.size());
  for (size_t i = 0; i < area.size(); ++i) area[i] = mesh.patches[i].area;
  for (std::int32_t z = 0; z < zones.size(); ++z) area.push_back(zones.area[z]);
  const SparseF T = one.F.transpose();
  for (std::int32_t i = 0; i < one.F.rows(); ++i)
    for (SparseF::InnerIterator it(one.F, i); it; ++it) {
      const double g = area[i] * it.value(), h = area[it.col()] * T.coeff(i, it.col());
      ASSERT_NEAR(g, h, 1e-12 * std::max(g, h)) << i << " " << it.col();  // a few roundings
    }
}

TEST(MediumFurnace, PurelyScatteringMediumKeepsEOverOneMinusRho) {
  // sigma_a = 0: zones have albedo 1 and no emission; walls rho 0.5, E 1: B = 2 everywhere.
  CubeCase c;
  build_cube(c, 0.5, 1.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(2.0),
             Eigen::Vector3d::Zero(), 4);
  ASSERT_EQ(c.zones.size(), 64);
  const double err = expect_uniform(c.problem, 2.0);
  std::printf("furnace: max |B - 2| / 2 = %.3g\n", err);
  // Meaningful by itself: the walls' row sums are 1 to the analytic factors' accuracy and
  // the zones' exactly (every ray ends in a zone or on a wall), so B is E/(1 - rho) to the
  // row-sum error times the amplification (< 20 here): 1e-4 is that bound with a margin.
  EXPECT_LE(err, 1e-4);
}

TEST(MediumKirchhoff, IsothermalEnclosureHasUniformRadiance) {
  // Walls rho 0.3 emitting (1 - rho) pi L_b, a medium absorbing 1, scattering 0.5, emitting
  // 4 pi sigma_a L_b per volume; L_b = 1/pi: every unknown's B = pi L_b = 1.
  CubeCase c;
  build_cube(c, 0.3, 0.7, Eigen::Vector3d::Constant(1.0), Eigen::Vector3d::Constant(0.5),
             Eigen::Vector3d::Constant(4.0), 3);
  // The zone's emitted radiosity e / (4 sigma_t) is (1 - albedo) pi L_b.
  EXPECT_NEAR(c.zones.emission(0, 0), 1.0 - c.zones.albedo(0, 0), 1e-15);
  const double err = expect_uniform(c.problem, 1.0);
  std::printf("kirchhoff: max |B - 1| = %.3g\n", err);
  EXPECT_LE(err, 1e-4);  // as in the furnace
  // Energy balance: every unknown absorbs what it emits (net exchange 0), so the power
  // emitted equals the power absorbed, surfaces plus medium, to the same bound.
  const RadiositySolution s = solve_direct(c.problem);
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_LE(s.energy[ch].relative_imbalance, 1e-9);
    EXPECT_NEAR(s.energy[ch].escaped / s.energy[ch].emitted, 0.0, 1e-4);
  }
}

TEST(MediumSolvers, EverySolverMatchesDirectOnTheExtendedSystem) {
  // Walls rho 0.5 (one emitting), a medium of albedo 0.5: rho_max = 0.5 and every row sums
  // to <= 1, so ||rho F||_inf <= 0.5 and ||B - B*||_inf <= ||K^-1||_inf ||r||_inf
  // <= tol ||E||_2 / (1 - 0.5) for a solver stopped at relative residual tol.
  CubeCase c;
  build_cube(c, 0.5, 0.0, Eigen::Vector3d::Constant(0.5), Eigen::Vector3d::Constant(0.5),
             Eigen::Vector3d::Zero(), 3);
  for (std::int32_t i = 0; i < c.mesh.size(); ++i)
    if (c.mesh.patches[i].surface == 3) c.problem.emission.row(i).setConstant(1.0);
  const RadiositySolution ref = solve_direct(c.problem);
  for (const std::string& name : solver_names()) {
    if (name == "direct") continue;
    SolveOptions so;
    so.solver = name;
    so.tol = 1e-10;
    const RadiositySolution s = solve_radiosity(c.problem, so);
    ASSERT_EQ(s.status, SolveStatus::Converged) << name;
    for (int ch = 0; ch < 3; ++ch) {
      const double bound = so.tol * c.problem.emission.col(ch).norm() / (1 - 0.5);
      EXPECT_LE((s.B.col(ch) - ref.B.col(ch)).cwiseAbs().maxCoeff(), bound) << name;
    }
  }
}

TEST(MediumSlabSlow, PlateExchangeThroughAbsorbingSlabMatchesTwoE3) {
  // Plates W x W at distance d = 1, a purely absorbing slab of optical thickness tau = 1
  // filling the prism between them (every ray between the plates stays inside it).
  const double W = 8.0, d = 1.0, tau = 1.0;
  const PatchMesh mesh = mesh_scene(opposed_squares(W, d), {1.0, 0});
  const Medium medium =
      homogeneous_medium({0, 0, 0}, {W, W, d}, {8, 8, 1}, Eigen::Vector3d::Constant(tau / d),
                         Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  const Zones zones = make_zones(medium);
  const FormFactors surface = surface_factors(mesh, "analytic");
  // Plane-parallel closed form for infinite plates: F = 2 E3(tau). The finite plates'
  // exact factor is F = (1/W²) ∫∫ k(|x - y|) dx dy, k(s) = d² exp(-sigma r) / (pi r⁴),
  // r² = d² + s²; with the square's autocorrelation, F = (4/W²) ∫_[0,W]² k(u) (W - u_x)
  // (W - u_y) du: composite 8-point Gauss-Legendre on 32 panels per axis (the integrand is
  // analytic with width ~d = 1 panel = 0.25: error far below 1e-10). 2 E3 - F is the
  // finite-size effect.
  const double two_e3 = 2.0 * e3_partial(tau, 1.0);
  static const double gx[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                               -0.1834346424956498, 0.1834346424956498,  0.5255324099163290,
                               0.7966664774136267,  0.9602898564975363};
  static const double gw[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                               0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                               0.2223810344533745, 0.1012285362903763};
  std::vector<double> nodes, weights;
  const int panels = 32;
  for (int p = 0; p < panels; ++p)
    for (int k = 0; k < 8; ++k) {
      const double h = W / panels;
      nodes.push_back((p + 0.5 * (gx[k] + 1)) * h);
      weights.push_back(0.5 * h * gw[k]);
    }
  double exact = 0.0;
  for (size_t a = 0; a < nodes.size(); ++a)
    for (size_t b = 0; b < nodes.size(); ++b) {
      const double r2 = d * d + nodes[a] * nodes[a] + nodes[b] * nodes[b];
      const double k = d * d * std::exp(-tau / d * std::sqrt(r2)) / (M_PI * r2 * r2);
      exact += weights[a] * weights[b] * k * (W - nodes[a]) * (W - nodes[b]);
    }
  exact *= 4.0 / (W * W);
  // Replicates: the transmittance's Monte Carlo error from R = 8 seeds (the estimator's own
  // spread).
  const int R = 8;
  std::vector<double> f(R);
  const double area_a = W * W;
  for (int r = 0; r < R; ++r) {
    const FormFactors ext = extended_factors(mesh, medium, zones, surface, 100 + r, 64, 64);
    for (std::int32_t i = 0; i < mesh.size(); ++i) {
      if (mesh.patches[i].surface != 0) continue;
      for (SparseF::InnerIterator it(ext.F, i); it; ++it)
        if (it.col() < mesh.size() && mesh.patches[it.col()].surface == 1)
          f[r] += mesh.patches[i].area * it.value() / area_a;
    }
  }
  double mean = 0.0, var = 0.0;
  for (double v : f) mean += v / R;
  for (double v : f) var += (v - mean) * (v - mean) / (R - 1);
  const double se = std::sqrt(var / R);
  std::printf(
      "slab: F_ab %.6f +- %.1e; exact finite plates %.6f; 2E3(1) %.6f "
      "(finite-size effect %.4f = %.1f%%)\n",
      mean, se, exact, two_e3, two_e3 - exact, 100 * (two_e3 - exact) / two_e3);
  EXPECT_NEAR(two_e3, 2 * 0.10969196719776, 1e-12);  // E3(1) (Abramowitz & Stegun 5.1)
  // 4 sigma of the replicates, plus the analytic factors' error: <= 1e-7 per entry, 64
  // entries per row of plate a, so <= 6.4e-6 on the area-weighted sum.
  EXPECT_NEAR(mean, exact, 4 * se + 6.4e-6);
}

}  // namespace lambert

namespace lambert {

using testing::run;
using testing::slurp;
using testing::TempDir;

TEST(MediumCli, FoggyCornellBoxEnergyBalanceCloses) {
  TempDir dir;
  ::testing::internal::CaptureStdout();
  const int code = run({"run",
                        "-o",
                        dir.file("out"),
                        "--patches",
                        "150",
                        "--samples",
                        "4",
                        "--size",
                        "48x48",
                        "-q",
                        "-j",
                        "2",
                        "--medium-box",
                        "0,0,0,556,548.8,559.2",
                        "--sigma-s",
                        "0.0005,0.0005,0.0005",
                        "--sigma-a",
                        "0.0002,0.0002,0.0002",
                        "--voxels",
                        "4",
                        "--medium-rays",
                        "64",
                        "--medium-emission",
                        "0,0,1e-4"});
  const std::string text = ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, kExitOk) << text;
  const nlohmann::json report = nlohmann::json::parse(slurp(dir.file("out/report.json")));
  const auto& medium = report.at("medium");
  EXPECT_EQ(medium.at("zones").get<int>(), 64);
  EXPECT_EQ(medium.at("resolution"), nlohmann::json({4, 4, 4}));
  for (int c = 0; c < 3; ++c) {
    const auto& e = report.at("energy_balance")[c];
    const double emitted = e.at("emitted").get<double>();
    const double absorbed = e.at("absorbed").get<double>();
    // Converged to tol 1e-8 on a reciprocal F (pair estimator, reciprocity-built zone
    // blocks): the imbalance is the residual part, |Σ A r| / emitted ~ 1e-8; 1e-6 margin.
    EXPECT_LE(e.at("relative_imbalance").get<double>(), 1e-6) << c;
    // The split: surfaces + medium = absorbed, sums of the same terms (rounding, 1e-12).
    const double s = medium.at("absorbed_surfaces")[c].get<double>();
    const double m = medium.at("absorbed_medium")[c].get<double>();
    EXPECT_NEAR(s + m, absorbed, 1e-12 * emitted) << c;
    EXPECT_GT(m, 0.0) << c;  // the fog absorbs
  }
  // The blue emission (1e-4 W/unit³ over the box's volume) is emitted power.
  const double volume = 556 * 548.8 * 559.2;
  EXPECT_GT(report.at("energy_balance")[2].at("emitted").get<double>(), 1e-4 * volume * 0.999);
  EXPECT_NE(text.find("absorbed by surfaces / by the medium"), std::string::npos);
}

TEST(MediumCli, RenderTakesTheMediumToo) {
  TempDir dir;
  const std::vector<std::string> fog = {"--medium-box",  "0,0,0,556,548.8,559.2",
                                        "--sigma-a",     "0.001,0.001,0.001",
                                        "--voxels",      "3",
                                        "--medium-rays", "32"};
  std::vector<std::string> args = {
      "render", "-o", dir.file("fog.exr"), "--patches", "100", "--samples", "4", "--size",
      "32x32",  "-q"};
  args.insert(args.end(), fog.begin(), fog.end());
  ::testing::internal::CaptureStdout();
  const int code = run(args);
  const std::string text = ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, kExitOk) << text;
  EXPECT_TRUE(std::filesystem::exists(dir.file("fog.png")));
  // A saved per-patch radiosity has no zones: refused with a medium.
  const std::string csv = dir.write("b.csv", "patch,R,G,B\n");
  std::vector<std::string> from_csv = {"render", "-o", dir.file("x.exr"), "--radiosity", csv, "-q"};
  from_csv.insert(from_csv.end(), fog.begin(), fog.end());
  EXPECT_EQ(run(from_csv), kExitUsage);
}

TEST(MediumCli, SolveWritesPatchesAndTheMediumSection) {
  TempDir dir;
  ::testing::internal::CaptureStdout();
  const int code = run({"solve", "-o", dir.file("b.csv"), "--patches", "100", "--samples", "4",
                        "-q", "--medium-box", "0,0,0,556,548.8,559.2", "--sigma-s",
                        "0.001,0.001,0.001", "--voxels", "2", "--medium-rays", "32"});
  const std::string text = ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, kExitOk) << text;
  const nlohmann::json j = nlohmann::json::parse(slurp(dir.file("b.json")));
  EXPECT_EQ(j.at("medium").at("zones").get<int>(), 8);
  // Purely scattering: the medium absorbs nothing (sums of exact zeros).
  EXPECT_EQ(j.at("medium").at("absorbed_medium")[0].get<double>(), 0.0);
  // The CSV holds the patches only (header + one line per patch).
  const std::string csv = slurp(dir.file("b.csv"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), j.at("patches").get<int>() + 1);
  for (const auto& ch : j.at("channels"))  // as in the run test: tol 1e-8, margin 100
    EXPECT_LE(ch.at("energy").at("relative_imbalance").get<double>(), 1e-6);
}

TEST(MediumCli, SavedSurfaceFactorsTakeTheMediumOnTop) {
  // --ff loads the surfaces' F; the medium is added on top: the same B as computing F here
  // with the same settings (the file stores doubles: bitwise the same F).
  TempDir dir;
  const std::vector<std::string> mesh = {"--patches", "80", "--samples", "4", "-q"};
  const std::vector<std::string> fog = {"--medium-box",  "0,0,0,556,548.8,559.2",
                                        "--sigma-a",     "0.001,0.001,0.001",
                                        "--voxels",      "2",
                                        "--medium-rays", "16"};
  auto args = [&](std::vector<std::string> a, bool with_mesh_counts) {
    if (with_mesh_counts)
      a.insert(a.end(), mesh.begin(), mesh.end());
    else
      a.insert(a.end(), {"--patches", "80", "-q"});
    a.insert(a.end(), fog.begin(), fog.end());
    return a;
  };
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(
      run({"formfactors", "-o", dir.file("F.bin"), "--patches", "80", "--samples", "4", "-q"}),
      kExitOk);
  ASSERT_EQ(run(args({"solve", "-o", dir.file("a.csv")}, true)), kExitOk);
  ASSERT_EQ(run(args({"solve", "-o", dir.file("b.csv"), "--ff", dir.file("F.bin")}, false)),
            kExitOk);
  ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(slurp(dir.file("a.csv")), slurp(dir.file("b.csv")));
}

// The fog of the saved-F tests: 2³ zones of sigma_t 0.0015 / mm.
std::vector<std::string> saved_fog(const std::string& sigma_a, const std::string& sigma_s) {
  return {"--medium-box",
          "0,0,0,556,548.8,559.2",
          "--sigma-a",
          sigma_a,
          "--sigma-s",
          sigma_s,
          "--voxels",
          "2",
          "--medium-rays",
          "16",
          "--transmittance-samples",
          "4"};
}

std::vector<std::string> joined(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

TEST(MediumCli, FormFactorsSavesTheZonesAndSolveReusesThem) {
  // `formfactors` with a medium writes the extended F (patches, then zones); `solve --ff`
  // with the same medium takes it as it is: the same B as computing everything in `solve`
  // (same seed; .bin stores doubles, .mtx writes %.17g: both round-trip bit for bit).
  TempDir dir;
  const std::vector<std::string> fog = saved_fog("0.0005,0.0005,0.0005", "0.001,0.001,0.001");
  const std::vector<std::string> mesh = {"--patches", "80", "-q"};
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(
      run(joined(joined({"formfactors", "-o", dir.file("F.bin"), "--samples", "4"}, mesh), fog)),
      kExitOk);
  ASSERT_EQ(
      run(joined(joined({"formfactors", "-o", dir.file("F.mtx"), "--samples", "4"}, mesh), fog)),
      kExitOk);
  ASSERT_EQ(run(joined(joined({"solve", "-o", dir.file("a.csv"), "--samples", "4"}, mesh), fog)),
            kExitOk);
  ASSERT_EQ(
      run(joined(joined({"solve", "-o", dir.file("b.csv"), "--ff", dir.file("F.bin")}, mesh), fog)),
      kExitOk);
  ASSERT_EQ(
      run(joined(joined({"solve", "-o", dir.file("c.csv"), "--ff", dir.file("F.mtx")}, mesh), fog)),
      kExitOk);
  ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(slurp(dir.file("a.csv")), slurp(dir.file("b.csv")));
  EXPECT_EQ(slurp(dir.file("a.csv")), slurp(dir.file("c.csv")));
  const nlohmann::json report = nlohmann::json::parse(slurp(dir.file("F.report.json")));
  EXPECT_EQ(report.at("medium").at("zones").get<int>(), 8);
  EXPECT_NE(report.at("settings").get<std::string>().find("medium_zones=8"), std::string::npos);
  // The summary says the zones came with the file.
  const nlohmann::json b = nlohmann::json::parse(slurp(dir.file("b.json")));
  EXPECT_TRUE(b.at("medium").at("loaded").get<bool>());
  EXPECT_EQ(b.at("medium").at("rays_per_unknown").get<int>(), 16);
}

TEST(MediumCli, SavedZonesServeAnyAlbedoOfTheSameExtinction) {
  // F depends on the extinction only: the saved zones with another albedo (same sigma_t =
  // 0.0015) give bitwise the B of computing F with that albedo; another extinction is
  // refused (exit 1), and no medium at all is a usage error (exit 2).
  TempDir dir;
  const std::vector<std::string> mesh = {"--patches", "80", "-q"};
  const std::vector<std::string> grey = saved_fog("0.0005,0.0005,0.0005", "0.001,0.001,0.001");
  const std::vector<std::string> tinted = saved_fog("0.001,0.0005,0", "0.0005,0.001,0.0015");
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(
      run(joined(joined({"formfactors", "-o", dir.file("F.bin"), "--samples", "4"}, mesh), grey)),
      kExitOk);
  ASSERT_EQ(run(joined(joined({"solve", "-o", dir.file("a.csv"), "--samples", "4"}, mesh), tinted)),
            kExitOk);
  ASSERT_EQ(run(joined(joined({"solve", "-o", dir.file("b.csv"), "--ff", dir.file("F.bin")}, mesh),
                       tinted)),
            kExitOk);
  ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(slurp(dir.file("a.csv")), slurp(dir.file("b.csv")));
  const std::vector<std::string> thicker = saved_fog("0.001,0.001,0.001", "0.001,0.001,0.001");
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(run(joined(joined({"solve", "-o", dir.file("c.csv"), "--ff", dir.file("F.bin")}, mesh),
                       thicker)),
            kExitFailure);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("another participating medium"),
            std::string::npos);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(run(joined({"solve", "-o", dir.file("d.csv"), "--ff", dir.file("F.bin")}, mesh)),
            kExitUsage);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("F.bin: holds the exchange factors"),
            std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.csv")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("d.csv")));
}

TEST(MediumCli, CompareRunsEverySolverOnTheExtendedSystem) {
  // The command compares on patches + zones: each solver reaches its stopping rule there
  // (their agreement with direct within tol ||E|| / (1 - rho_max) on the extended system is
  // MediumSolvers.EverySolverMatchesDirectOnTheExtendedSystem).
  TempDir dir;
  const std::vector<std::string> fog = saved_fog("0.0005,0.0005,0.0005", "0.001,0.001,0.001");
  ::testing::internal::CaptureStdout();
  ASSERT_EQ(run(joined({"compare", "-o", dir.file("cmp") + "/", "--patches", "80", "--samples", "4",
                        "-q", "--tol", "1e-8", "--solvers", "jacobi,gauss-seidel,bicgstab,direct"},
                       fog)),
            kExitOk);
  const std::string text = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(text.find("+ 8 medium zones"), std::string::npos) << text;
  const std::string table = slurp(dir.file("cmp/compare_table.csv"));
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 5) << table;  // header + 4 solvers
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n') - 1, [&] {
    int converged = 0;
    for (size_t at = 0; (at = table.find(",converged,", at)) != std::string::npos; ++at)
      ++converged;
    return converged;
  }()) << table;
  // The hierarchical comparison has no medium.
  EXPECT_EQ(
      run(joined({"compare", "-o", dir.file("h") + "/", "--method", "hierarchical", "-q"}, fog)),
      kExitUsage);
}

TEST(MediumCli, TheMemoryEstimateCountsTheZones) {
  // 32³ zones at 256 rays need gigabytes (media.hpp: medium_peak_bytes; 6.1 GB measured on
  // the Cornell box): under a 200 MiB limit the job is refused before any work, naming the
  // medium, while the same job without the medium (1.6 k patches, < 60 MiB) fits.
  TempDir dir;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(
      run({"formfactors", "-o", dir.file("F.bin"), "-q", "--max-memory", "200M", "--medium-box",
           "0,0,0,556,548.8,559.2", "--sigma-a", "0.001,0.001,0.001", "--voxels", "32"}),
      kExitUsage);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("the medium's zones"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir.file("F.bin")));
  // --stderr: the zones carry no standard errors yet: refused, not silently dropped.
  EXPECT_EQ(run({"formfactors", "-o", dir.file("F.bin"), "--stderr", "-q", "--medium-box",
                 "0,0,0,556,548.8,559.2", "--sigma-a", "0.001,0.001,0.001"}),
            kExitUsage);
}

TEST(MediumCli, HeterogeneousGridFileIsRead) {
  TempDir dir;
  std::string grid = "# two voxels along x\nbounds 0 0 0 556 548.8 559.2\nresolution 2 1 1\n";
  grid += "0.0002 0.0002 0.0002 0.0005 0.0005 0.0005 0 0 0\n";
  grid += "0 0 0 0 0 0 0 0 0  # clear\n";
  const std::string path = dir.write("fog.txt", grid);
  ::testing::internal::CaptureStdout();
  const int code = run({"run", "-o", dir.file("out"), "--patches", "100", "--samples", "4",
                        "--size", "32x32", "-q", "--medium-grid", path, "--medium-rays", "32"});
  const std::string text = ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, kExitOk) << text;
  const nlohmann::json report = nlohmann::json::parse(slurp(dir.file("out/report.json")));
  EXPECT_EQ(report.at("medium").at("zones").get<int>(), 1);  // the clear voxel is no zone
  EXPECT_EQ(report.at("medium").at("source"), path);
}

TEST(MediumCli, BadMediaAreClearErrors) {
  TempDir dir;
  const std::vector<std::string> base = {"run", "-o", dir.file("out"), "--patches", "50", "-q"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    return run(a);
  };
  // Coefficients without a box; coloured extinction; an inverted box; a negative value.
  EXPECT_EQ(with({"--sigma-a", "1,1,1"}), kExitUsage);
  EXPECT_EQ(with({"--medium-box", "0,0,0,1,1,1", "--sigma-a", "1,2,1"}), kExitUsage);
  EXPECT_EQ(with({"--medium-box", "0,0,0,-1,1,1", "--sigma-a", "1,1,1"}), kExitUsage);
  EXPECT_EQ(with({"--medium-box", "0,0,0,1,1,1", "--sigma-a", "-1,-1,-1"}), kExitUsage);
  // Not with the hierarchical method, raytrace shading or exact-direct vertices.
  // (Without --patches, which hierarchical refuses first: the refusal must name the medium.)
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(run({"run", "-o", dir.file("out"), "-q", "--medium-box", "0,0,0,1,1,1", "--sigma-a",
                 "1,1,1", "--method", "hierarchical"}),
            kExitUsage);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("--medium-box"), std::string::npos);
  EXPECT_EQ(with({"--medium-box", "0,0,0,1,1,1", "--sigma-a", "1,1,1", "--shading", "raytrace"}),
            kExitUsage);
  // A grid file with a bad line: exit 1, the message names file and line.
  const std::string bad = dir.write("bad.txt",
                                    "bounds 0 0 0 1 1 1\nresolution 1 1 2\n"
                                    "1 1 1 0 0 0 0 0 0\n1 1 1 0 0 0 0 0 -1\n");
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(with({"--medium-grid", bad}), kExitFailure);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("bad.txt:4"), std::string::npos);
  const std::string short_grid =
      dir.write("short.txt", "bounds 0 0 0 1 1 1\nresolution 2 1 1\n1 1 1 0 0 0 0 0 0\n");
  EXPECT_EQ(with({"--medium-grid", short_grid}), kExitFailure);
  // A grid with --voxels (the grid sets its resolution).
  const std::string good =
      dir.write("good.txt", "bounds 0 0 0 1 1 1\nresolution 1 1 1\n1 1 1 0 0 0 0 0 0\n");
  EXPECT_EQ(with({"--medium-grid", good, "--voxels", "4"}), kExitUsage);
}

TEST(MediumCli, AHugeBoxRunsAndCoefficientsNoDoubleHoldsAreRefused) {
  TempDir dir;
  auto solve = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = {"solve", "-o", dir.file("b.csv"), "--patches", "20", "-q"};
    a.insert(a.end(), extra.begin(), extra.end());
    return run(a);
  };
  // Issue 33, item 5: a box reaching +-2e18 (the Cornell box is ~500 across) aborted in an
  // Embree assertion (exit 134). In the power-of-two frame of the BVH it runs: exit 0.
  EXPECT_EQ(solve({"--medium-box", "-2e18,-2e18,-2e18,2e18,2e18,2e18", "--sigma-a",
                   "1e-19,1e-19,1e-19", "--voxels", "1"}),
            kExitOk);
  // Coefficients whose optical thickness no double holds: refused in one line.
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--medium-box", "0,0,0,500,500,500", "--sigma-a",
                                 "1e-320,1e-320,1e-320"},
        std::vector<std::string>{"--medium-box", "0,0,0,500,500,500", "--sigma-s",
                                 "1e300,1e300,1e300"}}) {
    ::testing::internal::CaptureStderr();
    const int code = solve(extra);
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(code, kExitUsage) << extra[3];
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
}

}  // namespace lambert
