#pragma once
// Error estimates of the ray-traced estimators by randomised quasi-Monte Carlo replicates
// (internal).
//
// The k samples of an estimate are split into R = min(k, kReplicates) replicates, each a
// low-discrepancy point set with its own random shift, so the R replicate estimates are
// independent and identically distributed. The variance of their mean is estimated by
// s² / R (unbiased, whatever the lattice's variance reduction: the sample variance of
// the k correlated points would overstate the error of a lattice 3-11 x). The standard
// error reported is that estimate's square root times c(R - 1) = t_{R-1}(0.97725) / 2, so
// that ± 2 stderr is a 95.45 % interval of Student's t with R - 1 degrees of freedom, as
// ± 2σ is for the normal law; for R = 16, c = 1.09.

#include <algorithm>
#include <cmath>

namespace lambert::ff {

/// Most replicates per estimate.
constexpr int kReplicates = 16;

/// Replicates for k samples.
inline int replicate_count(int samples) { return std::max(1, std::min(samples, kReplicates)); }

/// Samples of replicate r (0-based): k / R, the first k mod R ones get one more.
inline int replicate_size(int samples, int r) {
  const int R = replicate_count(samples);
  return samples / R + (r < samples % R ? 1 : 0);
}

/// Variance to report for the mean of R i.i.d. replicate estimates `est` (see above);
/// 0 when R < 2 (no estimate possible).
inline double replicate_variance(const double* est, int R) {
  if (R < 2) return 0.0;
  // t_{nu}(0.97725) / 2 for nu = 1..30 (computed by bisection of the t distribution
  // function); beyond 30, 1 + 1.3 / nu (within 1e-3 of the exact value).
  static constexpr double kT[30] = {6.9839, 2.2633, 1.6534, 1.4347, 1.3243, 1.2583, 1.2144,
                                    1.1832, 1.1599, 1.1418, 1.1274, 1.1157, 1.1059, 1.0976,
                                    1.0906, 1.0845, 1.0791, 1.0744, 1.0702, 1.0665, 1.0632,
                                    1.0601, 1.0574, 1.0548, 1.0525, 1.0504, 1.0485, 1.0467,
                                    1.0450, 1.0434};
  double mean = 0.0;
  for (int r = 0; r < R; ++r) mean += est[r] / R;
  double s2 = 0.0;
  for (int r = 0; r < R; ++r) s2 += (est[r] - mean) * (est[r] - mean) / (R - 1);
  const int nu = R - 1;
  const double c = nu <= 30 ? kT[nu - 1] : 1.0 + 1.3 / nu;
  return c * c * s2 / R;
}

}  // namespace lambert::ff
