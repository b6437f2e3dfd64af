// satmesh wait ID [--poll S] [--timeout S] [--quiet]
#include <cstdio>

#include "client/args.h"
#include "client/command.h"
#include "client/remote_client.h"

namespace satmesh::cli {
namespace {

int RunWait(const std::vector<std::string>& argv) {
  const Args args(argv, {"help", "quiet"});
  if (args.Has("help") || args.positionals().size() != 1) {
    std::printf("usage: satmesh wait ID [--poll 0.5] [--timeout S] [--quiet] [--server URL] [--token T]\n"
                "  Follows the job with a progress bar until it ends: exit 0 successful,\n"
                "  3 failed or dismissed, 1 timeout.\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  return RunRemote([&] {
    const auto info = WaitForJob(RemoteClient::FromArgs(args), args.positionals()[0],
                                 args.GetDouble("poll", 0.5), args.GetDouble("timeout", 0),
                                 args.Has("quiet"));
    std::printf("%s\n", FormatStatusLine(info).c_str());
    return ExitCodeForStatus(info);
  });
}

}  // namespace

SATMESH_REGISTER_COMMAND("wait", "wait for a remote job, with a progress bar", RunWait);

}  // namespace satmesh::cli
