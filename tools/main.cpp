/// @file main.cpp
/// The `qsil` command-line program: dispatches to the subcommands registered in tools/cmd_*.cpp.
/// Errors are one line on stderr; exit code 2 for bad input (qsil::Error), 1 for internal errors.

#include "cli_parse.h"
#include "commands.h"
#include "qsil/error.h"

#include <algorithm>
#include <iostream>

namespace qsil::cli {
std::vector<Command>& command_registry() {
  static std::vector<Command> registry;
  return registry;
}
}  // namespace qsil::cli

int main(int argc, char** argv) {
  using namespace qsil::cli;
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
  if (const auto code = qsil::cli::parse_arguments(app, argc, argv)) return *code;
  try {
    for (auto& [sub, run] : runners)
      if (sub->parsed()) return run();
  } catch (const qsil::Error& e) {
    std::cerr << "qsil: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "qsil: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
