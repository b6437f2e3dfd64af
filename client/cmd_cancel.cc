// satmesh cancel ID
#include <cstdio>

#include "client/args.h"
#include "client/command.h"
#include "client/remote_client.h"

namespace satmesh::cli {
namespace {

int RunCancel(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || args.positionals().size() != 1) {
    std::printf("usage: satmesh cancel ID [--server URL] [--token T]\n"
                "  Cancels the job's running tiles and dismisses it (its outputs are removed).\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  return RunRemote([&] {
    const auto info = RemoteClient::FromArgs(args).Delete("/jobs/" + args.positionals()[0]).Json();
    std::printf("%s\n", FormatStatusLine(info).c_str());
    return int(kExitOk);
  });
}

}  // namespace

SATMESH_REGISTER_COMMAND("cancel", "cancel and dismiss a remote job", RunCancel);

}  // namespace satmesh::cli
