// satmesh jobs [--status S] [--limit N] [--json]
#include <cstdio>

#include "client/args.h"
#include "client/command.h"
#include "client/remote_client.h"

namespace satmesh::cli {
namespace {

int RunJobs(const std::vector<std::string>& argv) {
  const Args args(argv, {"help", "json"});
  if (args.Has("help") || !args.positionals().empty()) {
    std::printf("usage: satmesh jobs [--status accepted|running|successful|failed|dismissed]\n"
                "         [--limit N] [--json] [--server URL] [--token T]\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  return RunRemote([&] {
    std::string query = "/jobs?limit=" + std::to_string(args.GetInt("limit", 100));
    if (args.Has("status")) query += "&status=" + args.Require("status");
    const auto list = RemoteClient::FromArgs(args).Get(query).Json();
    if (args.Has("json")) std::printf("%s\n", list.dump(2).c_str());
    else
      for (const auto& job : list["jobs"]) std::printf("%s\n", FormatStatusLine(job).c_str());
    return int(kExitOk);
  });
}

}  // namespace

SATMESH_REGISTER_COMMAND("jobs", "list the server's jobs", RunJobs);

}  // namespace satmesh::cli
