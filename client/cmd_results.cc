// satmesh results ID --out DIR
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "client/args.h"
#include "client/command.h"
#include "client/refine_runner.h"
#include "client/remote_client.h"

namespace satmesh::cli {
namespace {
namespace fs = std::filesystem;

int RunResults(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || args.positionals().size() != 1 || !args.Has("out")) {
    std::printf("usage: satmesh results ID --out DIR [--server URL] [--token T]\n"
                "  Downloads tileset.json, tiles/*.glb, metrics.json, mesh.ply, dsm.tif, preview.png and\n"
                "  convergence.png, and writes viewer.html (+ a Cesium link) as satmesh refine does.\n"
                "  Exit 4 while the job is not done (result-not-ready), 3 when it failed.\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  return RunRemote([&] {
    const std::string id = args.positionals()[0];
    const fs::path out = args.Require("out");
    const RemoteClient client = RemoteClient::FromArgs(args);
    const auto response = client.Get("/jobs/" + id + "/results", /*allow_error=*/true);
    if (response.status == 422) throw RemoteError(kExitJobFailed, "job " + id + " failed: " + response.body);
    if (response.status >= 400) client.Get("/jobs/" + id + "/results");  // throws with the detail
    const auto results = response.Json();
    fs::create_directories(out / "tiles");
    size_t files = 0, bytes = 0;
    for (const char* name : {"tileset", "metrics", "mesh", "dsm", "preview", "convergence"}) {
      if (!results.contains(name) || !results[name].contains("href")) continue;
      const std::string href = results[name]["href"];
      bytes += client.Download(href, (out / fs::path(href).filename()).string());
      ++files;
    }
    for (const auto& tile : results["tiles"]) {
      if (!tile.contains("href")) continue;
      const std::string href = tile["href"];
      bytes += client.Download(href, (out / "tiles" / fs::path(href).filename()).string());
      ++files;
    }
    std::printf("%zu files, %zu bytes -> %s\n", files, bytes, out.string().c_str());
    WriteViewer(out.string());  // the downloaded tileset, viewable as refine's
    return int(kExitOk);
  });
}

}  // namespace

SATMESH_REGISTER_COMMAND("results", "download a remote job's results", RunResults);

}  // namespace satmesh::cli
