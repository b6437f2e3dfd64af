// satmesh status ID [--json]
#include <cstdio>

#include "client/args.h"
#include "client/command.h"
#include "client/remote_client.h"

namespace satmesh::cli {
namespace {

int RunStatus(const std::vector<std::string>& argv) {
  const Args args(argv, {"help", "json"});
  if (args.Has("help") || args.positionals().size() != 1) {
    std::printf("usage: satmesh status ID [--json] [--server URL] [--token T]\n"
                "  Prints the job's status (exit 0 when the job exists, 4 when not).\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  return RunRemote([&] {
    const auto info = RemoteClient::FromArgs(args).Get("/jobs/" + args.positionals()[0]).Json();
    std::printf("%s\n", args.Has("json") ? info.dump(2).c_str() : FormatStatusLine(info).c_str());
    return int(kExitOk);
  });
}

}  // namespace

SATMESH_REGISTER_COMMAND("status", "a remote job's status", RunStatus);

}  // namespace satmesh::cli
