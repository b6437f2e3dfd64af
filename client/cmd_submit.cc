// satmesh submit JOB.json [--wait] [--set key=value ...] [--idempotency-key K] [--as-written]
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "client/args.h"
#include "client/command.h"
#include "client/remote_client.h"
#include "proto/job_spec_json.h"

namespace satmesh::cli {
namespace {
namespace fs = std::filesystem;

// Relative hrefs made absolute against the job file's directory, as `satmesh refine` reads
// them (a server that sees this machine's files at the same paths takes them as they are);
// the server still checks them against its data roots.
void MakeHrefsAbsolute(nlohmann::json* job, const fs::path& base) {
  auto fix = [&](nlohmann::json& href) {
    if (!href.is_string()) return;
    const std::string h = href;
    if (!h.empty() && h.rfind("/vsi", 0) != 0 && fs::path(h).is_relative())
      href = fs::absolute(base / h).lexically_normal().string();
  };
  if (job->contains("images") && (*job)["images"].is_array())
    for (auto& image : (*job)["images"])
      if (image.is_object() && image.contains("href")) fix(image["href"]);
  if (job->contains("initial") && (*job)["initial"].is_object() && (*job)["initial"].contains("dsm"))
    fix((*job)["initial"]["dsm"]);
}

int RunSubmit(const std::vector<std::string>& argv) {
  const Args args(argv, {"help", "wait", "absolute", "as-written", "quiet"});
  if (args.Has("help") || args.positionals().size() != 1) {
    std::printf(
        "usage: satmesh submit JOB.json [--wait] [--set key=value ...] [--as-written]\n"
        "         [--idempotency-key K] [--server URL] [--token T]\n"
        "  Submits the job to satmesh-server and prints its id. Relative hrefs are resolved\n"
        "  against the job file's directory (as `satmesh refine` does) and sent as absolute\n"
        "  paths, which the server must see under one of its --data-root folders; with\n"
        "  --as-written they are sent unchanged and the server resolves them against its\n"
        "  first data root (the files copied there). --absolute: the default, kept for scripts.\n"
        "  --wait follows the job to its end (exit 0 successful, 3 failed).\n"
        "  Server and token also from SATMESH_SERVER and SATMESH_TOKEN. Exit codes: 0 ok,\n"
        "  1 failure, 2 usage, 3 job failed, 4 not found, 5 unreachable, 6 auth, 7 rejected.\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  return RunRemote([&] {
    const std::string path = args.positionals()[0];
    std::ifstream in(path);
    if (!in) throw RemoteError(kExitUsage, "job file '" + path + "' cannot be opened");
    nlohmann::json job;
    try {
      job = nlohmann::json::parse(in);
    } catch (const std::exception& e) {
      throw RemoteError(kExitUsage, "job file '" + path + "': invalid JSON: " + e.what());
    }
    for (const auto& o : args.GetAll("set")) proto::ApplyOptionOverride(&job, o);
    const bool as_written = args.Has("as-written");
    if (as_written && args.Has("absolute")) throw RemoteError(kExitUsage, "--as-written and --absolute exclude each other");
    if (!as_written) MakeHrefsAbsolute(&job, fs::absolute(path).parent_path());
    const RemoteClient client = RemoteClient::FromArgs(args);
    nlohmann::json info;
    try {
      info = client.Post("/processes/refine-mesh/execution", job.dump(), args.GetOr("idempotency-key", "")).Json();
    } catch (const RemoteError& e) {
      const std::string what = e.what();
      const bool href = what.find(".href") != std::string::npos || what.find("initial.dsm") != std::string::npos;
      if (!href) throw;
      throw RemoteError(e.exit_code(), what + "\n" + (as_written
          ? "hint: with --as-written the server resolves hrefs against its first --data-root; copy the "
            "job's files there, or submit without --as-written (paths resolved here)"
          : "hint: the hrefs were resolved against '" + fs::absolute(path).parent_path().lexically_normal().string() +
            "' and sent as absolute paths; the server must see them there, under one of its --data-root "
            "folders (e.g. satmesh-server --data-root " + fs::absolute(path).parent_path().lexically_normal().string() +
            "). A server on another machine: copy the job's folder under its data root and submit with "
            "--as-written"));
    }
    const std::string id = info["jobID"];
    std::printf("%s\n", id.c_str());
    std::fflush(stdout);
    if (!args.Has("wait")) return int(kExitOk);
    const auto final_info = WaitForJob(client, id, args.GetDouble("poll", 0.5),
                                       args.GetDouble("timeout", 0), args.Has("quiet"));
    std::fprintf(stderr, "%s\n", FormatStatusLine(final_info).c_str());
    return ExitCodeForStatus(final_info);
  });
}

}  // namespace

SATMESH_REGISTER_COMMAND("submit", "submit a job to satmesh-server (remote)", RunSubmit);

}  // namespace satmesh::cli
