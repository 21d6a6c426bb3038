// libFuzzer target: the arguments of `lambert.solve` in Python, through the C++ entry points
// the module calls with them: F's three CSR arrays (io/array_args: csr_from_arrays, with any
// shape, a decreasing or overshooting indptr, indices out of range, non-finite values), the
// (N, 3) tables for E, rho and the initial guess (rows_of_three), the solver's name and
// numbers, then validate_problem and solve_radiosity on what was accepted. A lambert::Error
// is a clean refusal; a crash, a sanitizer report, another exception, or an accepted solve
// whose B is not finite is a bug.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/array_args.hpp"
#include "solvers/operator.hpp"
#include "solvers/radiosity.hpp"

namespace {

using lambert::ArrayArg;

// A value that is often one of the troublesome ones.
double number(FuzzedDataProvider& in) {
  static const double kSpecial[] = {0.0,
                                    -0.0,
                                    1.0,
                                    -1.0,
                                    0.5,
                                    1e-320,
                                    1e308,
                                    -1e308,
                                    2.0,
                                    10.0,
                                    1e-9,
                                    std::numeric_limits<double>::infinity(),
                                    std::numeric_limits<double>::quiet_NaN()};
  if (in.ConsumeBool()) return in.PickValueInArray(kSpecial);
  return in.ConsumeFloatingPoint<double>();
}

std::int64_t index(FuzzedDataProvider& in, std::int64_t n) {
  if (in.ConsumeIntegralInRange(0, 15) == 0) return in.ConsumeIntegral<std::int64_t>();
  return in.ConsumeIntegralInRange<std::int64_t>(-2, n + 2);
}

// An array with its shape: usually `want` (the expected shape), sometimes another.
template <typename T, typename Gen>
ArrayArg<T> array(FuzzedDataProvider& in, std::vector<T>& store, std::vector<std::int64_t> want,
                  Gen gen) {
  if (in.ConsumeIntegralInRange(0, 7) == 0) {  // another shape: other sizes or dimensions
    want.resize(in.ConsumeIntegralInRange<std::size_t>(0, 3));
    for (auto& d : want) d = in.ConsumeIntegralInRange<std::int64_t>(0, 9);
  }
  std::int64_t size = 1;
  for (const auto d : want) size *= d;
  store.resize(static_cast<std::size_t>(size));
  for (auto& v : store) v = gen();
  return {store.data(), want};
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool quiet = (lambert::set_log_level(lambert::LogLevel::Quiet), true);
  (void)quiet;
  FuzzedDataProvider in(data, size);
  const std::int64_t n = in.ConsumeIntegralInRange<std::int64_t>(0, 6);
  const std::int64_t nnz = in.ConsumeIntegralInRange<std::int64_t>(0, n * n + 2);
  std::vector<std::int64_t> indptr_store, indices_store;
  std::vector<double> data_store, e_store, rho_store, guess_store;
  // indptr: a plausible running count (what scipy holds) or arbitrary entries.
  const bool running = in.ConsumeBool();
  std::int64_t at = 0;
  const auto indptr = array<std::int64_t>(in, indptr_store, {n + 1}, [&]() -> std::int64_t {
    if (!running) return index(in, nnz);
    const std::int64_t v = at;
    at = std::min(nnz, at + in.ConsumeIntegralInRange<std::int64_t>(0, n));
    return v;
  });
  if (running && !indptr_store.empty()) indptr_store.back() = nnz;
  const auto indices = array<std::int64_t>(in, indices_store, {nnz}, [&] { return index(in, n); });
  const auto values = array<double>(in, data_store, {nnz}, [&] { return number(in) * 0.25; });
  const auto e = array<double>(in, e_store, {n, 3}, [&] { return number(in); });
  const auto rho = array<double>(in, rho_store, {n, 3}, [&] { return number(in); });
  const bool guess = in.ConsumeBool();
  const auto initial = array<double>(in, guess_store, {n, 3}, [&] { return number(in); });
  const std::vector<std::string> names = lambert::solver_names();
  lambert::SolveOptions o;
  o.solver = in.ConsumeBool() ? names[in.ConsumeIntegralInRange<std::size_t>(0, names.size() - 1)]
                              : in.ConsumeRandomLengthString(12);
  o.tol = number(in);
  o.max_iterations = in.ConsumeIntegralInRange(-1, 64);
  o.omega = number(in);
  o.restart = in.ConsumeIntegralInRange(-1, 40);
  o.threads = 1;
  try {
    const lambert::SparseRowMatrix F = lambert::csr_from_arrays(n, indptr, indices, values, "F");
    lambert::RadiosityProblem p;
    p.F = std::make_shared<lambert::CsrOperator>(F);
    p.emission = lambert::rows_of_three(e, n, "emission");
    p.rho = lambert::rows_of_three(rho, n, "reflectance");
    p.area = Eigen::VectorXd::Ones(n);
    if (guess) o.initial_guess = lambert::rows_of_three(initial, n, "initial_guess");
    lambert::validate_problem(p);
    const lambert::RadiositySolution s = lambert::solve_radiosity(p, o);
    if (!s.B.allFinite()) std::abort();
  } catch (const lambert::Error&) {
  }
  return 0;
}
