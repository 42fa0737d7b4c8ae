#pragma once
/// @file distributed.h
/// Runs split across processes and machines with MPI (docs/architecture.md §12): the estimator
/// layer's runs divided into parts, one per process (rank), and combined into exactly — bit for
/// bit — the result of one process, for any number of processes and threads.
///
/// The split. Part r of R (RenderOptions::part, parts) renders every sample of the run's range
/// for the pixels whose index y W + x is r mod R (Film::part_of), and the r-th of R contiguous
/// shares of the primary boundary term's chunks. Each pixel's sums are formed by one process in
/// the single-process order; the film is then passed along the ranks, each copying its pixels in
/// (copies, not sums) and adding its splats in order (merge_part), the last sending it to rank 0.
/// Why not sum per-process films: floating-point addition is not associative; this split performs
/// every floating-point operation of the single-process run, in its order.
///
/// Only this file's implementation (integrators/distributed.cpp) includes MPI; a build without
/// MPI (CMake option QSIL_MPI) has the same interface with one process.

#include "qsil/error.h"
#include "qsil/integrators/estimator.h"

#include <cstdint>
#include <string>

namespace qsil {

/// Adds part `part` of `parts` of one run (RenderOptions::part, parts; its film holds that part's
/// pixels, RenderResult::splats its primary boundary splats) to `whole`: its pixels are copied
/// into whole's film and its splats added in order; counters add (seconds: the maximum).
/// Parts must be added in order 0, 1, ..., parts - 1, starting from a default RenderResult; then
/// `whole` equals the whole run's result (Estimator::run with parts = 1) bit for bit in every
/// film value and counter except the times. Throws nothing; a film of another size or layout than
/// the previous parts' is a bug (checked).
void merge_part(RenderResult& whole, const RenderResult& part_result, int part, int parts);

/// Runs `options` as `parts` parts, one after the other in this process, and combines them with
/// merge_part: the result a distributed run over `parts` processes returns on rank 0 (the
/// definition that tests compare with a single run). Throws qsil::Error as Estimator::run.
RenderResult run_in_parts(const Estimator& estimator, RenderOptions options, int parts);

/// An error that every process of a group agreed on (ProcessGroup::agree): every rank throws it,
/// rank 0 reports it and every rank exits with exit_code() (2 for bad input, 1 internal).
class GroupError : public Error {
 public:
  GroupError(const std::string& message, int exit_code) : Error(message), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

/// The processes of one qsil job: the ranks of MPI_COMM_WORLD when the program was started by an
/// MPI launcher, else one process. One object per program, made in main() before anything else
/// and destroyed last (it initialises and finalises MPI). Not copyable.
class ProcessGroup {
 public:
  /// A group of one process; MPI is not touched.
  ProcessGroup() = default;
  /// Joins the MPI job (MPI_Init_thread, funneled: only the main thread calls MPI) when the
  /// environment shows an MPI launcher (launcher_size() > 0: Open MPI's mpirun, a PMIx or PMI
  /// launcher such as srun) and this build has MPI; otherwise a group of one process, so that
  /// programs started without a launcher pay nothing (MPI_Init alone costs about a second).
  /// Throws GroupError (code 2) when a launcher started more than one process but this build has
  /// no MPI (every process would render the whole image).
  ProcessGroup(int& argc, char**& argv);
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  /// Rank 0: the process that prints and writes outputs.
  bool root() const { return rank_ == 0; }

  /// Collective (every rank must call it, in the same sequence of collective calls): each rank
  /// passes its outcome (an empty `local_error` for success; otherwise its one-line message and
  /// exit code). Returns when every rank succeeded; otherwise every rank throws GroupError with
  /// the message of the lowest failing rank (prefixed "rank N: " unless N = 0) and its code.
  void agree(const std::string& local_error = "", int local_code = 0) const;

  /// Collective: runs `step` on every rank and agrees on its outcome (agree): a qsil::Error is bad
  /// input (exit code 2), any other std::exception an internal error (1). So a failure on one rank
  /// (a scene file missing on one machine) ends every rank with one message, none hanging.
  template <class F>
  void all_or_none(F&& step) const {
    std::string error;
    int code = 0;
    try {
      step();
    } catch (const GroupError&) { throw; } catch (const Error& e) {
      error = e.what();
      code = 2;
    } catch (const std::exception& e) {
      error = std::string("internal error: ") + e.what();
      code = 1;
    }
    agree(error, code);
  }

  /// Collective: renders `options` split into size() parts, this process's part rank() (progress
  /// bar on rank 0 only). On rank 0 returns the whole run's result, bit-identical in every film
  /// value and counter to `estimator.run(options)` in one process (merge_part); its `seconds` is
  /// the wall time of the distributed run, communication included, and `boundary_seconds` the
  /// largest part's. Other ranks return their part's result (not the whole film). A rank whose run
  /// throws ends every rank with GroupError (agree). In a group of one: estimator.run(options).
  RenderResult run(const Estimator& estimator, RenderOptions options) const;

  /// Collective: the sum of `value` over the ranks, on every rank.
  uint64_t sum(uint64_t value) const;

  /// Ends every process of the job with exit code `code` (MPI_Abort; std::exit in a group of one)
  /// after the caller printed why: for a failure outside a collective step, where the other ranks
  /// may be waiting for this one.
  [[noreturn]] void abort(int code) const;

  /// Whether this build has MPI (CMake option QSIL_MPI).
  static bool built_with_mpi();
  /// The number of processes an MPI launcher started, from the environment it sets:
  /// OMPI_COMM_WORLD_SIZE (Open MPI's mpirun), PMI_SIZE (MPICH's Hydra, srun --mpi=pmi2), or with
  /// PMIX_RANK (a PMIx launcher: Open MPI 5, srun --mpi=pmix) SLURM_NTASKS, or -1 if unknown;
  /// 0 when no launcher started this process.
  static int launcher_size();
  /// This process's rank according to the launcher's environment (0 without a launcher).
  static int launcher_rank();

 private:
  int rank_ = 0;
  int size_ = 1;
  bool mpi_ = false;  ///< joined an MPI job (finalise in the destructor)
};

}  // namespace qsil
