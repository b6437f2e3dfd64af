#pragma once
// The stub server (satmesh-server-stub) as a child process on an ephemeral port.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>

namespace satmesh::server::testing {

struct Child {
  pid_t pid = -1;
  int port = 0;
};

// Starts the stub server and reads "listening on port N" from its stdout.
inline Child Spawn(const std::string& dir, int tiles_x = 4, int tiles_y = 2, int tile_ms = 300) {
  const std::string tx = std::to_string(tiles_x), ty = std::to_string(tiles_y), ms = std::to_string(tile_ms);
  int out[2];
  if (pipe(out) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    close(out[0]);
    const std::string data = dir + "/data", root = dir + "/root";
    execl(SATMESH_STUB_SERVER, SATMESH_STUB_SERVER, "--port", "0", "--data-dir", data.c_str(),
          "--data-root", root.c_str(), "--workers", "2", "--stub-tiles-x", tx.c_str(), "--stub-tiles-y", ty.c_str(),
          "--stub-tile-ms", ms.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(out[1]);
  FILE* f = fdopen(out[0], "r");
  char line[256] = {0};
  Child child{pid, 0};
  while (fgets(line, sizeof line, f)) {
    if (std::sscanf(line, "listening on port %d", &child.port) == 1) break;
  }
  // Keep the pipe open (closing could SIGPIPE the child's later prints).
  return child;
}

inline int Stop(const Child& child) {
  kill(child.pid, SIGTERM);
  int status = 0;
  waitpid(child.pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace satmesh::server::testing
