// satmesh: the command-line front end. Each subcommand lives in client/cmd_<name>.cc.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <exception>

#include "client/command.h"
#include "core/common/error.h"

namespace satmesh::cli {
std::vector<Command>& CommandRegistry() {
  static std::vector<Command> commands;
  return commands;
}
}  // namespace satmesh::cli

namespace {
void PrintUsage() {
  auto commands = satmesh::cli::CommandRegistry();
  std::sort(commands.begin(), commands.end(),
            [](const auto& a, const auto& b) { return a.name < b.name; });
  std::printf("usage: satmesh <command> [options]   (satmesh <command> --help)\n\ncommands:\n");
  for (const auto& c : commands) std::printf("  %-10s %s\n", c.name.c_str(), c.summary.c_str());
}
}  // namespace

int main(int argc, char** argv) {
  using namespace satmesh::cli;
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    PrintUsage();
    return argc < 2 ? kExitUsage : kExitOk;
  }
  const std::string name = argv[1];
  std::vector<std::string> args(argv + 2, argv + argc);
  for (const auto& c : CommandRegistry()) {
    if (c.name != name) continue;
    try {
      return c.run(args);
    } catch (const satmesh::Error& e) {
      spdlog::error("{} ({})", e.what(), satmesh::ErrorCodeName(e.code()));
      return e.code() == satmesh::ErrorCode::kInvalidArgument ? kExitUsage : kExitFailure;
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kExitFailure;
    }
  }
  std::fprintf(stderr, "satmesh: unknown command '%s'\n", name.c_str());
  PrintUsage();
  return kExitUsage;
}
