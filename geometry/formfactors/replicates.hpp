#pragma once
// Error estimates of the ray-traced estimators by randomised quasi-Monte Carlo replicates
// (internal).
//
// The k samples of an estimate are split into R = min(k, kReplicates) replicates, each a
// low-discrepancy point set with its own random shift, so the R replicate estimates are
// independent and identically distributed. The variance of their mean is estimated by
// s² / R (unbiased, whatever the lattice's variance reduction: the sample variance of
// the k correlated points would overstate the error of a lattice 3-11 x). The standard
// error reported is that estimate's square root times c(R - 1) = t_{R-1}(0.985) / 2, so
// that ± 2 stderr is a 97 % interval of Student's t with R - 1 degrees of freedom (a
// margin over the 95.45 % of ± 2σ for the normal law, so that "within ± 2 stderr in at
// least 95 % of cases" holds with room for the non-normal tails of few-ray estimates);
// for R = 16, c = 1.19: the reported stderr is 1.19 x the replicates' standard error.

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
  // t_{nu}(0.985) / 2 for nu = 1..30 (bisection of the t distribution function); beyond
  // 30, the normal limit 1.085 + 1.6 / nu (within 2e-3).
  static constexpr double kT[30] = {10.6025, 2.8214, 1.9480, 1.6488, 1.5014, 1.4145, 1.3573,
                                    1.3169,  1.2869, 1.2637, 1.2453, 1.2304, 1.2179, 1.2074,
                                    1.1985,  1.1908, 1.1840, 1.1781, 1.1728, 1.1681, 1.1639,
                                    1.1601,  1.1566, 1.1535, 1.1506, 1.1479, 1.1455, 1.1432,
                                    1.1411,  1.1391};
  double mean = 0.0;
  for (int r = 0; r < R; ++r) mean += est[r] / R;
  double s2 = 0.0;
  for (int r = 0; r < R; ++r) s2 += (est[r] - mean) * (est[r] - mean) / (R - 1);
  const int nu = R - 1;
  const double c = nu <= 30 ? kT[nu - 1] : 1.085 + 1.6 / nu;
  return c * c * s2 / R;
}

}  // namespace lambert::ff
