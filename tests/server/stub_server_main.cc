// satmesh-server with the stub engine (tests/server/stub_executor.h), for process-level
// tests (kill -9 and restart, the CLI against a server) that must not refine for real.
#include <spdlog/spdlog.h>

#include "core/common/error.h"
#include "server/server_cli.h"
#include "tests/server/stub_executor.h"

int main(int argc, char** argv) {
  using namespace satmesh::server;
  try {
    std::map<std::string, std::string> extra;
    const auto options = ParseServerArgs({argv + 1, argv + argc},
                                         {"stub-tiles-x", "stub-tiles-y", "stub-tile-ms", "stub-fail-tile"}, &extra);
    testing::StubOptions stub;
    if (extra.count("stub-tiles-x")) stub.tiles_x = std::stoi(extra["stub-tiles-x"]);
    if (extra.count("stub-tiles-y")) stub.tiles_y = std::stoi(extra["stub-tiles-y"]);
    if (extra.count("stub-tile-ms")) stub.tile_ms = std::stoi(extra["stub-tile-ms"]);
    if (extra.count("stub-fail-tile")) stub.fail_tile = extra["stub-fail-tile"];
    testing::StubExecutor executor(stub);
    return ServeUntilSignal(options, &executor);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}
