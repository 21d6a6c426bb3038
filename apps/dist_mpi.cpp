// MPI for the distributed commands (see dist_mpi.hpp). PETSc starts and ends MPI here too,
// so that the solve (dist_petsc.cpp) shares the communicator PETSC_COMM_WORLD.
#include "apps/dist_mpi.hpp"

#include <mpi.h>
#include <petscsys.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <new>
#include <thread>

#include "core/error.hpp"

namespace lambert::dist {
namespace {

MPI_Comm comm() { return PETSC_COMM_WORLD; }

// Counts and displacements in units of one element for MPI's int-counted calls; throws
// when a rank's share exceeds what an int counts (2^31 elements; docs/cluster.md "Running on a
// cluster": more ranks then).
int count_of(std::int64_t n) {
  if (n > 2147483647) throw Error("a message of more than 2^31 elements: use more ranks");
  return static_cast<int>(n);
}

// One entry on the wire: row, column, value, standard error (24 bytes).
struct WireEntry {
  std::int32_t row, col;
  double value, err;
};

MPI_Datatype wire_type() {
  static MPI_Datatype type = [] {
    MPI_Datatype t;
    MPI_Type_contiguous(sizeof(WireEntry), MPI_BYTE, &t);
    MPI_Type_commit(&t);
    return t;
  }();
  return type;
}

}  // namespace

Session::Session(const std::string& petsc_options) {
  PetscErrorCode e = PetscInitializeNoArguments();
  if (e) throw Error("PETSc (and MPI) could not be initialised");
  // Errors come back as codes (dist_petsc.cpp turns them into exceptions) instead of a
  // traceback on every rank.
  PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
  MPI_Comm_rank(comm(), &rank_);
  MPI_Comm_size(comm(), &size_);
  MPI_Comm node;
  MPI_Comm_split_type(comm(), MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &node_ranks_);
  MPI_Comm_free(&node);
  // After MPI is up, so that a bad option string fails the job on every rank alike.
  if (!petsc_options.empty() && PetscOptionsInsertString(nullptr, petsc_options.c_str())) {
    PetscFinalize();  // no destructor runs for a constructor that throws
    throw UsageError("--petsc-options: PETSc cannot parse '" + petsc_options + "'");
  }
}

Session::~Session() { PetscFinalize(); }

int Session::default_threads() const {
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, cores / node_ranks_);
}

void collective(const std::function<void()>& stage) {
  int code = 0;
  std::string message;
  try {
    stage();
  } catch (const UsageError& e) {
    code = 2, message = e.what();
  } catch (const Error& e) {
    code = 1, message = e.what();
  } catch (const std::bad_alloc&) {
    code = 1, message = "out of memory";
  } catch (const std::exception& e) {
    code = 1, message = e.what();
  }
  int rank = 0, size = 1;
  MPI_Comm_rank(comm(), &rank);
  MPI_Comm_size(comm(), &size);
  const int mine = code ? rank : size;
  int first = size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm());
  if (first == size) return;
  MPI_Bcast(&code, 1, MPI_INT, first, comm());
  int length = static_cast<int>(message.size());
  MPI_Bcast(&length, 1, MPI_INT, first, comm());
  message.resize(static_cast<size_t>(length));
  MPI_Bcast(message.data(), length, MPI_CHAR, first, comm());
  throw Failure{code, first == 0 ? message : "rank " + std::to_string(first) + ": " + message};
}

int run_job(const std::string& petsc_options, const std::function<int(const Session&)>& job) {
  std::unique_ptr<Session> session;
  try {
    session = std::make_unique<Session>(petsc_options);
  } catch (const Error& e) {  // the same on every rank: each prints, rank 0 alone if known
    int rank = 0, up = 0, down = 0;
    MPI_Initialized(&up);
    MPI_Finalized(&down);
    if (up && !down)
      MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    else if (const char* r = std::getenv("OMPI_COMM_WORLD_RANK"))
      rank = std::atoi(r);
    if (rank == 0) std::cerr << "lambert: " << e.what() << '\n';
    return dynamic_cast<const UsageError*>(&e) ? 2 : 1;
  }
  try {
    return job(*session);
  } catch (const Failure& f) {
    if (session->root()) std::cerr << "lambert: " << f.message << '\n';
    return f.code;
  } catch (const std::exception& e) {
    // Outside a collective stage the other ranks may be waiting in a collective call:
    // only an abort ends them.
    std::cerr << "lambert: rank " << session->rank() << ": " << e.what() << '\n';
    MPI_Abort(comm(), 1);
    return 1;
  }
}

double sum(double x) {
  double out = 0.0;
  MPI_Allreduce(&x, &out, 1, MPI_DOUBLE, MPI_SUM, comm());
  return out;
}

std::int64_t sum(std::int64_t x) {
  std::int64_t out = 0;
  MPI_Allreduce(&x, &out, 1, MPI_INT64_T, MPI_SUM, comm());
  return out;
}

double max(double x) {
  double out = 0.0;
  MPI_Allreduce(&x, &out, 1, MPI_DOUBLE, MPI_MAX, comm());
  return out;
}

bool all_equal(std::uint64_t x) {
  std::uint64_t lo = 0, hi = 0;
  MPI_Allreduce(&x, &lo, 1, MPI_UINT64_T, MPI_MIN, comm());
  MPI_Allreduce(&x, &hi, 1, MPI_UINT64_T, MPI_MAX, comm());
  return lo == hi;
}

std::vector<double> gather(double x) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm(), &rank);
  MPI_Comm_size(comm(), &size);
  std::vector<double> all(rank == 0 ? size : 0);
  MPI_Gather(&x, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, 0, comm());
  return all;
}

double peak_memory_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return 1024.0 * static_cast<double>(usage.ru_maxrss);  // Linux: kilobytes
}

std::vector<std::int32_t> row_partition(std::int32_t n, int ranks) {
  return balanced_pair_rows(n, ranks);
}

RowBlock exchange_mirrors(const FormFactors& partial, const std::vector<std::int32_t>& rows) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm(), &rank);
  MPI_Comm_size(comm(), &size);
  const SparseF& F = partial.F;
  const bool with_err = partial.stderr_F.nonZeros() == F.nonZeros() && F.nonZeros() > 0;
  const auto n = static_cast<std::int32_t>(F.rows());
  // Entries by destination: the owner of their row (rows are in increasing order, and so
  // are the owners).
  std::vector<int> send_count(size, 0), recv_count(size, 0);
  std::vector<WireEntry> send;
  send.reserve(static_cast<size_t>(F.nonZeros()));
  int owner = 0;
  for (std::int32_t i = 0; i < n; ++i) {
    while (i >= rows[owner + 1]) ++owner;
    for (std::int64_t k = F.outerIndexPtr()[i]; k < F.outerIndexPtr()[i + 1]; ++k) {
      send.push_back({i, static_cast<std::int32_t>(F.innerIndexPtr()[k]), F.valuePtr()[k],
                      with_err ? partial.stderr_F.valuePtr()[k] : 0.0});
      ++send_count[owner];
    }
  }
  MPI_Alltoall(send_count.data(), 1, MPI_INT, recv_count.data(), 1, MPI_INT, comm());
  std::vector<int> send_at(size, 0), recv_at(size, 0);
  for (int r = 1; r < size; ++r) {
    send_at[r] = send_at[r - 1] + send_count[r - 1];
    recv_at[r] = recv_at[r - 1] + recv_count[r - 1];
  }
  std::vector<WireEntry> recv(static_cast<size_t>(recv_at[size - 1] + recv_count[size - 1]));
  MPI_Alltoallv(send.data(), send_count.data(), send_at.data(), wire_type(), recv.data(),
                recv_count.data(), recv_at.data(), wire_type(), comm());
  RowBlock block;
  block.begin = rows[rank];
  block.end = rows[rank + 1];
  block.sent_bytes = static_cast<std::int64_t>(send.size() - send_count[rank]) * sizeof(WireEntry);
  std::vector<WireEntry>().swap(send);
  // Each unordered pair was computed once, so no (row, column) arrives twice: sorting by
  // (row, column) gives the CSR.
  std::sort(recv.begin(), recv.end(), [](const WireEntry& a, const WireEntry& b) {
    return a.row != b.row ? a.row < b.row : a.col < b.col;
  });
  const auto nnz = static_cast<std::int64_t>(recv.size());
  block.F.resize(n, n);
  block.F.resizeNonZeros(nnz);
  if (with_err) {
    block.stderr_F.resize(n, n);
    block.stderr_F.resizeNonZeros(nnz);
  }
  auto* outer = block.F.outerIndexPtr();
  std::fill(outer, outer + n + 1, 0);
  for (std::int64_t k = 0; k < nnz; ++k) {
    const WireEntry& w = recv[k];
    LAMBERT_CHECK(w.row >= block.begin && w.row < block.end, "an entry reached the wrong rank");
    LAMBERT_CHECK(k == 0 || recv[k - 1].row != w.row || recv[k - 1].col != w.col,
                  "an entry arrived twice");
    ++outer[w.row + 1];
    block.F.innerIndexPtr()[k] = w.col;
    block.F.valuePtr()[k] = w.value;
    if (with_err) block.stderr_F.valuePtr()[k] = w.err;
  }
  for (std::int32_t i = 0; i < n; ++i) outer[i + 1] += outer[i];
  if (with_err) {
    std::copy(outer, outer + n + 1, block.stderr_F.outerIndexPtr());
    std::copy(block.F.innerIndexPtr(), block.F.innerIndexPtr() + nnz,
              block.stderr_F.innerIndexPtr());
  }
  return block;
}

void gather_rows(const RowBlock& block, std::int32_t n, SparseF& F, SparseF& stderr_F,
                 std::int64_t& bytes) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm(), &rank);
  MPI_Comm_size(comm(), &size);
  const bool with_err = block.stderr_F.rows() > 0;
  const auto* outer = block.F.outerIndexPtr();
  const std::int64_t first = outer[block.begin], mine = outer[block.end] - first;
  // Row lengths, then columns and values, each in rank (= row) order.
  std::vector<std::int64_t> lengths(static_cast<size_t>(block.end - block.begin));
  for (std::int32_t i = block.begin; i < block.end; ++i)
    lengths[i - block.begin] = outer[i + 1] - outer[i];
  const int count = count_of(mine);
  std::vector<int> rows_of(size), rows_at(size), nnz_of(size), nnz_at(size);
  const int my_rows = static_cast<int>(lengths.size());
  MPI_Gather(&my_rows, 1, MPI_INT, rows_of.data(), 1, MPI_INT, 0, comm());
  MPI_Gather(&count, 1, MPI_INT, nnz_of.data(), 1, MPI_INT, 0, comm());
  std::int64_t total = 0;
  for (int r = 0; rank == 0 && r < size; ++r) {
    rows_at[r] = r ? rows_at[r - 1] + rows_of[r - 1] : 0;
    nnz_at[r] = count_of(total);
    total += nnz_of[r];
  }
  F = SparseF();
  stderr_F = SparseF();
  if (rank == 0) {
    F.resize(n, n);
    F.resizeNonZeros(total);
    F.outerIndexPtr()[0] = 0;
    if (with_err) {
      stderr_F.resize(n, n);
      stderr_F.resizeNonZeros(total);
    }
  }
  MPI_Gatherv(lengths.data(), my_rows, MPI_INT64_T, rank == 0 ? F.outerIndexPtr() + 1 : nullptr,
              rows_of.data(), rows_at.data(), MPI_INT64_T, 0, comm());
  static_assert(sizeof(SparseF::StorageIndex) == 8, "F has 64-bit indices");
  MPI_Gatherv(block.F.innerIndexPtr() + first, count, MPI_INT64_T,
              rank == 0 ? F.innerIndexPtr() : nullptr, nnz_of.data(), nnz_at.data(), MPI_INT64_T, 0,
              comm());
  MPI_Gatherv(block.F.valuePtr() + first, count, MPI_DOUBLE, rank == 0 ? F.valuePtr() : nullptr,
              nnz_of.data(), nnz_at.data(), MPI_DOUBLE, 0, comm());
  if (with_err)
    MPI_Gatherv(block.stderr_F.valuePtr() + first, count, MPI_DOUBLE,
                rank == 0 ? stderr_F.valuePtr() : nullptr, nnz_of.data(), nnz_at.data(), MPI_DOUBLE,
                0, comm());
  bytes = rank == 0 ? 0 : 8 * (my_rows + 2 * mine + (with_err ? mine : 0));
  if (rank != 0) return;
  auto* o = F.outerIndexPtr();
  for (std::int32_t i = 0; i < n; ++i) o[i + 1] += o[i];
  if (with_err) {
    std::copy(o, o + n + 1, stderr_F.outerIndexPtr());
    std::copy(F.innerIndexPtr(), F.innerIndexPtr() + total, stderr_F.innerIndexPtr());
  }
}

RowBlock slice_rows(const FormFactors& ff, const std::vector<std::int32_t>& rows, int rank) {
  RowBlock block;
  block.begin = rows[rank];
  block.end = rows[rank + 1];
  const auto n = static_cast<std::int32_t>(ff.F.rows());
  const auto* outer = ff.F.outerIndexPtr();
  const std::int64_t first = outer[block.begin], nnz = outer[block.end] - first;
  block.F.resize(n, n);
  block.F.resizeNonZeros(nnz);
  auto* o = block.F.outerIndexPtr();
  for (std::int32_t i = 0; i <= n; ++i)
    o[i] = std::clamp<std::int64_t>(outer[std::clamp(i, block.begin, block.end)] - first, 0, nnz);
  std::copy(ff.F.innerIndexPtr() + first, ff.F.innerIndexPtr() + first + nnz,
            block.F.innerIndexPtr());
  std::copy(ff.F.valuePtr() + first, ff.F.valuePtr() + first + nnz, block.F.valuePtr());
  return block;
}

std::vector<double> allgather_rows(const std::vector<double>& local,
                                   const std::vector<std::int32_t>& rows) {
  const int size = static_cast<int>(rows.size()) - 1;
  std::vector<int> count(size), at(size);
  for (int r = 0; r < size; ++r) count[r] = rows[r + 1] - rows[r], at[r] = rows[r];
  std::vector<double> all(static_cast<size_t>(rows.back()));
  MPI_Allgatherv(local.data(), static_cast<int>(local.size()), MPI_DOUBLE, all.data(), count.data(),
                 at.data(), MPI_DOUBLE, comm());
  return all;
}

}  // namespace lambert::dist
