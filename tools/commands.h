#pragma once
/// @file commands.h
/// Subcommand registry of the `qsil` program. Each tools/cmd_NAME.cpp registers one subcommand
/// with a static `CommandRegistrar`, so adding a subcommand touches one file only.
/// A subcommand's run function returns the process exit code (0 ok, 2 bad input, 1 internal).

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace qsil::cli {

/// One subcommand: `setup` adds its options to the CLI11 subcommand and returns the function that
/// runs it after parsing.
struct Command {
  std::string name;
  std::string description;
  std::function<std::function<int()>(CLI::App&)> setup;
};

std::vector<Command>& command_registry();

struct CommandRegistrar {
  explicit CommandRegistrar(Command c) { command_registry().push_back(std::move(c)); }
};

}  // namespace qsil::cli
