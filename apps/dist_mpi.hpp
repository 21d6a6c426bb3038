#pragma once
// MPI for the distributed commands (LAMBERT_MPI builds only; no MPI type in this header).
// Collective rules: every rank calls these functions in the same order; a stage that may
// fail on some ranks runs inside collective(), so that no rank waits for a failed one.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "geometry/formfactors/formfactors.hpp"

namespace lambert::dist {

/// The MPI (and PETSc) lifetime of one distributed command: PetscInitialize (which starts
/// MPI) with `petsc_options` inserted, PetscFinalize at the end.
class Session {
 public:
  explicit Session(const std::string& petsc_options);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  bool root() const { return rank_ == 0; }
  /// Threads per rank for -j 0: the cores divided among the ranks on this node.
  int default_threads() const;

 private:
  int rank_ = 0, size_ = 1, node_ranks_ = 1;
};

/// A stage failed on some rank: thrown on every rank with the failing rank's exit code
/// (2 usage, 1 otherwise) and message (of the lowest failing rank).
struct Failure {
  int code;
  std::string message;
};

/// Runs `stage` on this rank, catching what it throws, then agrees with every rank: when
/// any failed, throws Failure everywhere. Collective.
void collective(const std::function<void()>& stage);

/// Runs a distributed command: `job` on every rank; a Failure (or an exception outside a
/// collective stage, which aborts the job: MPI_Abort) is printed by rank 0 alone as
/// "lambert: MESSAGE" and becomes the exit code of every rank.
int run_job(const std::string& petsc_options, const std::function<int(const Session&)>& job);

/// Sums (or maxima) over the ranks. Collective.
double sum(double x);
std::int64_t sum(std::int64_t x);
double max(double x);
/// True when every rank holds the same value. Collective.
bool all_equal(std::uint64_t x);

/// Every rank's x on rank 0, in rank order (empty elsewhere). Collective.
std::vector<double> gather(double x);

/// Peak resident memory of this process (bytes; getrusage).
double peak_memory_bytes();

/// First rows of the ranks (size() + 1 entries) for n patches: balanced_pair_rows.
std::vector<std::int32_t> row_partition(std::int32_t n, int ranks);

/// This rank's rows of F: an n x n CSR with rows [begin, end) filled (other rows empty, so
/// row-wise kernels run on it unchanged), and its standard errors when computed.
struct RowBlock {
  std::int32_t begin = 0, end = 0;
  SparseF F, stderr_F;
  std::int64_t sent_bytes = 0;  ///< bytes this rank sent in the mirror exchange
};

/// Completes this rank's rows from `partial` (compute_form_factors over this rank's row
/// range: both entries of each of its pairs) by sending every entry to its row's owner and
/// merging what arrives; columns sorted, values untouched. Collective.
RowBlock exchange_mirrors(const FormFactors& partial, const std::vector<std::int32_t>& rows);

/// The rows of every rank on rank 0, in order (an empty matrix elsewhere): the F a
/// single-process run computes. `bytes` gets what this rank sent. Collective.
void gather_rows(const RowBlock& block, std::int32_t n, SparseF& F, SparseF& stderr_F,
                 std::int64_t& bytes);

/// A row block of a complete F (from --ff): rows [rows[rank], rows[rank + 1]).
RowBlock slice_rows(const FormFactors& ff, const std::vector<std::int32_t>& rows, int rank);

/// Every rank's values concatenated in rank order (block r has rows[r + 1] - rows[r]
/// values), on every rank. Collective.
std::vector<double> allgather_rows(const std::vector<double>& local,
                                   const std::vector<std::int32_t>& rows);

}  // namespace lambert::dist
