// satmesh-server: the refinement service (OGC API - Processes over HTTP).
#include <spdlog/spdlog.h>

#include <cstdio>
#include <string>
#include <vector>

#include "core/common/error.h"
#include "server/real_executor.h"
#include "server/server_cli.h"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& a : args) {
    if (a == "--help" || a == "-h") {
      std::printf("%s", satmesh::server::ServerUsage().c_str());
      return 0;
    }
  }
  try {
    const auto options = satmesh::server::ParseServerArgs(args);
    satmesh::server::RealExecutor executor;
    return satmesh::server::ServeUntilSignal(options, &executor);
  } catch (const satmesh::Error& e) {
    spdlog::error("{}", e.what());
    return e.code() == satmesh::ErrorCode::kInvalidArgument ? 2 : 1;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
