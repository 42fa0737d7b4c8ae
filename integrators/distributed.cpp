/// @file distributed.cpp
/// Runs split into parts and combined, and the process group over MPI; see
/// qsil/integrators/distributed.h. The only file that includes MPI (when QSIL_HAVE_MPI is defined
/// by the CMake option QSIL_MPI); without it the group is always one process.

#include "qsil/integrators/distributed.h"

#include "qsil/check.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#ifdef QSIL_HAVE_MPI
#include <mpi.h>
#endif

namespace qsil {

// ---- Combining parts (no MPI)

void merge_part(RenderResult& whole, const RenderResult& p, int part, int parts) {
  QSIL_CHECK(parts >= 1 && part >= 0 && part < parts);
  if (parts == 1) {  // the whole run: its splats are in its film already
    whole = p;
    return;
  }
  if (part == 0) {
    whole = RenderResult();
    whole.film = Film(p.film.width(), p.film.height(), p.film.layout(), p.film.stratum_fraction());
    whole.first_sample = p.first_sample;
    whole.spp = p.spp;
  }
  QSIL_CHECK(whole.film.channels() == p.film.channels());
  // Pixels: copied from the one part that summed them (Film::part_of).
  whole.film.copy_part(p.film, part, parts);
  // Primary boundary splats: added after those of parts 0 .. part - 1, in the part's order, so
  // every splat sum is formed in the order of the whole run.
  for (const FilmSplat& s : p.splats) whole.film.splat(s.x, s.y, s.channel, s.value);
  whole.rays += p.rays;
  whole.nonfinite += p.nonfinite;
  whole.traversals += p.traversals;
  whole.zero_traversals += p.zero_traversals;
  whole.seconds = std::max(whole.seconds, p.seconds);
  whole.boundary_seconds = std::max(whole.boundary_seconds, p.boundary_seconds);
}

RenderResult run_in_parts(const Estimator& estimator, RenderOptions options, int parts) {
  if (parts < 1) throw Error("parts must be >= 1 (got " + std::to_string(parts) + ")");
  RenderResult whole;
  for (int part = 0; part < parts; ++part) {
    options.part = part;
    options.parts = parts;
    merge_part(whole, estimator.run(options), part, parts);
  }
  return whole;
}

// ---- The launcher's environment

namespace {

/// The integer value of environment variable `name`, or `fallback` when it is unset or not a
/// number.
int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  if (!v || !*v) return fallback;
  char* end = nullptr;
  const long n = std::strtol(v, &end, 10);
  return *end == '\0' ? int(n) : fallback;
}

}  // namespace

int ProcessGroup::launcher_size() {
  if (const int n = env_int("OMPI_COMM_WORLD_SIZE", 0); n > 0) return n;
  if (const int n = env_int("PMI_SIZE", 0); n > 0) return n;
  if (std::getenv("PMIX_RANK")) return env_int("SLURM_NTASKS", -1);
  return 0;
}

int ProcessGroup::launcher_rank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
    if (const int r = env_int(name, -1); r >= 0) return r;
  return 0;
}

#ifdef QSIL_HAVE_MPI

// ---- The process group over MPI

namespace {

constexpr int kTagCounters = 1, kTagFilm = 2;
/// Doubles per message: MPI counts are ints; 2^27 doubles = 1 GiB.
constexpr size_t kPiece = size_t(1) << 27;

/// Sends a (partly combined) result to rank `dest`: its counters, film size and film state.
void send_result(const RenderResult& r, int dest) {
  const uint64_t counters[] = {r.rays,
                               r.nonfinite,
                               r.traversals,
                               r.zero_traversals,
                               uint64_t(r.first_sample),
                               uint64_t(r.spp),
                               uint64_t(r.film.width()),
                               uint64_t(r.film.height()),
                               uint64_t(r.film.layout().num_params())};
  const double times[] = {r.seconds, r.boundary_seconds, r.film.stratum_fraction()};
  MPI_Send(counters, std::size(counters), MPI_UINT64_T, dest, kTagCounters, MPI_COMM_WORLD);
  MPI_Send(times, std::size(times), MPI_DOUBLE, dest, kTagCounters, MPI_COMM_WORLD);
  const std::vector<double> state = r.film.state();
  for (size_t i = 0; i < state.size(); i += kPiece)
    MPI_Send(state.data() + i, int(std::min(kPiece, state.size() - i)), MPI_DOUBLE, dest, kTagFilm, MPI_COMM_WORLD);
}

/// Waits for `request` without spinning a core: Open MPI's blocking calls poll, which on a
/// machine whose cores are all busy (oversubscribed ranks, other jobs) takes a core from the ranks
/// still rendering. For small messages only: a sleeping process does not advance a transfer.
void wait_politely(MPI_Request& request) {
  int done = 0;
  for (int i = 0;; ++i) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::microseconds(i < 100 ? 10 : 1000));
  }
}

/// Receives what send_result sent from rank `source`.
RenderResult receive_result(int source) {
  uint64_t counters[9];
  double times[3];
  MPI_Recv(counters, std::size(counters), MPI_UINT64_T, source, kTagCounters, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  MPI_Recv(times, std::size(times), MPI_DOUBLE, source, kTagCounters, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  RenderResult r;
  r.rays = counters[0];
  r.nonfinite = counters[1];
  r.traversals = counters[2];
  r.zero_traversals = counters[3];
  r.first_sample = int(counters[4]);
  r.spp = int(counters[5]);
  r.seconds = times[0];
  r.boundary_seconds = times[1];
  r.film = Film(int(counters[6]), int(counters[7]), FilmLayout(int(counters[8])), times[2]);
  std::vector<double> state(r.film.state_size());
  for (size_t i = 0; i < state.size(); i += kPiece)
    MPI_Recv(state.data() + i, int(std::min(kPiece, state.size() - i)), MPI_DOUBLE, source, kTagFilm, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
  r.film.set_state(state);
  return r;
}

}  // namespace

bool ProcessGroup::built_with_mpi() { return true; }

ProcessGroup::ProcessGroup(int& argc, char**& argv) {
  if (launcher_size() == 0) return;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  mpi_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

ProcessGroup::~ProcessGroup() {
  if (mpi_) MPI_Finalize();
}

void ProcessGroup::agree(const std::string& local_error, int local_code) const {
  if (size_ == 1) {
    if (!local_error.empty()) throw GroupError(local_error, local_code);
    return;
  }
  // The lowest failing rank (size_ when none failed) ...
  const int mine = local_error.empty() ? size_ : rank_;
  int first = size_;
  // Ranks that finish a step early (a render) wait here for the others: politely.
  MPI_Request request;
  MPI_Iallreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD, &request);
  wait_politely(request);
  if (first == size_) return;
  // ... tells every rank its message and exit code.
  int header[2] = {int(local_error.size()), local_code};
  MPI_Bcast(header, 2, MPI_INT, first, MPI_COMM_WORLD);
  std::string message = rank_ == first ? local_error : std::string(size_t(header[0]), ' ');
  MPI_Bcast(message.data(), header[0], MPI_CHAR, first, MPI_COMM_WORLD);
  throw GroupError(first == 0 ? message : "rank " + std::to_string(first) + ": " + message, header[1]);
}

RenderResult ProcessGroup::run(const Estimator& estimator, RenderOptions options) const {
  if (size_ == 1) {
    RenderResult r;
    all_or_none([&] { r = estimator.run(options); });
    return r;
  }
  const auto t0 = std::chrono::steady_clock::now();
  options.part = rank_;
  options.parts = size_;
  options.progress = options.progress && root();
  RenderResult mine;
  all_or_none([&] { mine = estimator.run(options); });
  // ---- The film goes along the ranks 0, 1, ..., size - 1 (merge_part: every part in order),
  // then back to rank 0.
  RenderResult whole;
  if (rank_ > 0) whole = receive_result(rank_ - 1);
  merge_part(whole, mine, rank_, size_);
  mine = RenderResult();  // its film and splats are in `whole` now
  send_result(whole, (rank_ + 1) % size_);
  if (!root()) return whole;
  whole = receive_result(size_ - 1);
  whole.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return whole;
}

uint64_t ProcessGroup::sum(uint64_t value) const {
  if (size_ == 1) return value;
  uint64_t total = 0;
  MPI_Allreduce(&value, &total, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  return total;
}

void ProcessGroup::abort(int code) const {
  std::fflush(stdout);
  std::fflush(stderr);
  if (mpi_) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

#else  // no MPI: a group of one process

bool ProcessGroup::built_with_mpi() { return false; }

ProcessGroup::ProcessGroup(int&, char**&) {
  const int n = launcher_size();
  if (n == 0 || n == 1) return;
  throw GroupError("started by an MPI launcher" +
                       (n > 1 ? " with " + std::to_string(n) + " processes" : std::string()) +
                       ", but this qsil was built without MPI, so every process would render the whole image (install "
                       "libopenmpi-dev and configure with -DQSIL_MPI=ON, or run qsil without mpirun)",
                   2);
}

ProcessGroup::~ProcessGroup() = default;

void ProcessGroup::agree(const std::string& local_error, int local_code) const {
  if (!local_error.empty()) throw GroupError(local_error, local_code);
}

RenderResult ProcessGroup::run(const Estimator& estimator, RenderOptions options) const {
  RenderResult r;
  all_or_none([&] { r = estimator.run(options); });
  return r;
}

uint64_t ProcessGroup::sum(uint64_t value) const { return value; }

void ProcessGroup::abort(int code) const {
  std::fflush(stdout);
  std::fflush(stderr);
  std::exit(code);
}

#endif

}  // namespace qsil
