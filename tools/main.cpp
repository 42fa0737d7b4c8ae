/// @file main.cpp
/// The `qsil` program: dispatches to the subcommands registered in tools/cmd_*.cpp.
/// Errors are one line on stderr; exit code 2 for bad input (qsil::Error), 1 for internal errors.
/// Started by an MPI launcher (`mpirun -np R qsil ...`, a build with MPI), the program is one rank
/// of a job (qsil/integrators/distributed.h): `render`, `grad`, `fd` and `reference` split their
/// work over the ranks, rank 0 prints and writes, and a failure on any rank ends every rank.

#include "cli_common.h"
#include "cli_parse.h"
#include "commands.h"
#include "qsil/error.h"
#include "qsil/integrators/distributed.h"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <iostream>
#include <optional>
#include <set>

namespace qsil::cli {
std::vector<Command>& command_registry() {
  static std::vector<Command> registry;
  return registry;
}
}  // namespace qsil::cli

namespace {

/// The subcommands that run split over the ranks of an MPI job.
const std::set<std::string> kDistributedCommands{"fd", "grad", "reference", "render"};

/// Rank 0's SIGTERM handler in a job of several ranks: the launcher ends the job this way when
/// another rank died (killed, crashed) or the job was interrupted; say so in one line, then end
/// as SIGTERM does. Only async-signal-safe calls.
extern "C" void on_terminate(int signal) {
  static const char message[] =
      "qsil: rank 0 ended by the MPI launcher (another rank failed or was killed, or the job was interrupted)\n";
  [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, message, sizeof message - 1);
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace qsil::cli;
  // ---- The process group first (MPI_Init may rewrite argv), destroyed last (MPI_Finalize).
  std::optional<qsil::ProcessGroup> group;
  try {
    group.emplace(argc, argv);
  } catch (const qsil::GroupError& e) {
    if (qsil::ProcessGroup::launcher_rank() == 0) std::cerr << "qsil: " << e.what() << "\n";
    return e.exit_code();
  }
  set_process_group(*group);
  if (group->size() > 1 && group->root()) std::signal(SIGTERM, on_terminate);
  CLI::App app{
      "qsil: a differentiable path tracer with quadric-based silhouette sampling "
      "(Soroka, Peters, Marschner 2025)."};
  app.require_subcommand(1);
  auto& registry = command_registry();
  std::sort(registry.begin(), registry.end(), [](const Command& a, const Command& b) { return a.name < b.name; });
  std::vector<std::pair<CLI::App*, std::function<int()>>> runners;
  for (auto& c : registry) {
    CLI::App* sub = app.add_subcommand(c.name, c.description);
    runners.emplace_back(sub, c.setup(*sub));
  }
  // Every rank parses the same arguments; rank 0 prints help and parse errors.
  if (const auto code = qsil::cli::parse_arguments(app, argc, argv, !group->root())) return *code;
  try {
    for (auto& [sub, run] : runners) {
      if (!sub->parsed()) continue;
      if (group->size() > 1 && !kDistributedCommands.count(sub->get_name()))
        group->agree("qsil " + sub->get_name() +
                         " does not run under an MPI launcher (render, grad, fd and "
                         "reference do): run it as one process",
                     2);
      return run();
    }
  } catch (const qsil::GroupError& e) {  // every rank has it: rank 0 reports
    // The job's outcome is said: when another rank exits first and the launcher ends this one
    // with SIGTERM, on_terminate must not add a second line.
    std::signal(SIGTERM, SIG_DFL);
    if (group->root()) std::cerr << "qsil: " << e.what() << "\n";
    return e.exit_code();
  } catch (const qsil::Error& e) {
    // Outside a collective step: this rank alone failed, and the others may be waiting for it.
    std::signal(SIGTERM, SIG_DFL);
    std::cerr << "qsil: " << (group->size() > 1 ? "rank " + std::to_string(group->rank()) + ": " : "") << e.what()
              << "\n";
    if (group->size() > 1) group->abort(2);
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "qsil: " << (group->size() > 1 ? "rank " + std::to_string(group->rank()) + ": " : "")
              << "internal error: " << e.what() << "\n";
    if (group->size() > 1) group->abort(1);
    return 1;
  }
  return 0;
}
