#pragma once
// Subcommands of the `satmesh` CLI register themselves here: one file per command
// (client/cmd_<name>.cc) with SATMESH_REGISTER_COMMAND. Exit codes: 0 ok, 1 failure,
// 2 usage error (see ExitCode).
#include <functional>
#include <string>
#include <vector>

namespace satmesh::cli {

enum ExitCode : int { kExitOk = 0, kExitFailure = 1, kExitUsage = 2 };

using CommandFn = std::function<int(const std::vector<std::string>& args)>;

struct Command {
  std::string name;
  std::string summary;  // one line for `satmesh --help`
  CommandFn run;
};

std::vector<Command>& CommandRegistry();

struct CommandRegistrar {
  CommandRegistrar(std::string name, std::string summary, CommandFn run) {
    CommandRegistry().push_back({std::move(name), std::move(summary), std::move(run)});
  }
};

}  // namespace satmesh::cli

#define SATMESH_REGISTER_COMMAND(name, summary, fn) \
  static ::satmesh::cli::CommandRegistrar satmesh_command_registrar_##fn(name, summary, fn)
