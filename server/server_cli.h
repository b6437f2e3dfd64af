#pragma once
// satmesh-server's command line, shared by the real binary and test binaries that plug
// in another engine.
#include <map>
#include <string>
#include <vector>

#include "server/api.h"

namespace satmesh::server {

// Parses --host --port --data-dir --data-root (repeatable) --allow-vsi (repeatable)
// --workers --token --max-body-bytes --max-images --max-tiles --max-pixels --proto-dir
// --http-threads --viewer-dir --cors-origin (repeatable); SATMESH_TOKEN in the environment sets the token, SATMESH_VIEWER_DIR the viewer folder. Options named in
// extra_keys go to *extra. Throws Error{kInvalidArgument} naming a bad option.
ServerOptions ParseServerArgs(const std::vector<std::string>& args,
                              const std::vector<std::string>& extra_keys = {},
                              std::map<std::string, std::string>* extra = nullptr);
std::string ServerUsage();
// Starts the server, prints "listening on port N" to stdout, serves until SIGINT or
// SIGTERM, stops cleanly. Returns the process exit code.
int ServeUntilSignal(const ServerOptions& options, JobExecutor* executor);

}  // namespace satmesh::server
