#pragma once
// The remote commands' connection to satmesh-server: --server/--token (or SATMESH_SERVER,
// SATMESH_TOKEN), JSON requests, RFC 7807 problems turned into errors, and exit codes
// that scripts can branch on.
#include <nlohmann/json.hpp>
#include <functional>
#include <memory>
#include <string>

#include "client/args.h"
#include "client/command.h"

namespace satmesh::cli {

// Exit codes of the remote commands (0/1/2 as every command; see client/command.h).
enum RemoteExitCode : int {
  kExitJobFailed = 3,    // the job ended failed (or dismissed)
  kExitNotFound = 4,     // no such job, or results not ready
  kExitUnreachable = 5,  // the server did not answer
  kExitAuth = 6,         // 401/403
  kExitRejected = 7,     // the server rejected the request (other 4xx)
};

// A failed request; exit_code is one of RemoteExitCode.
class RemoteError : public std::runtime_error {
 public:
  RemoteError(int exit_code, const std::string& message)
      : std::runtime_error(message), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

struct RemoteResponse {
  int status = 0;
  std::string body, content_type, location;
  nlohmann::json Json() const;  // throws RemoteError for a body that is not JSON
};

class RemoteClient {
 public:
  // server: "http://host:port" (default http://127.0.0.1:8080); token "" = none.
  RemoteClient(const std::string& server, const std::string& token);
  ~RemoteClient();
  // From --server/--token, else SATMESH_SERVER/SATMESH_TOKEN.
  static RemoteClient FromArgs(const Args& args);
  RemoteClient(RemoteClient&&) noexcept;

  // Throw RemoteError for no answer, and (unless allow_error) for a 4xx/5xx, with the
  // problem's detail in the message.
  RemoteResponse Get(const std::string& path, bool allow_error = false) const;
  RemoteResponse Post(const std::string& path, const std::string& json_body,
                      const std::string& idempotency_key = "") const;
  RemoteResponse Delete(const std::string& path) const;
  // Streams a GET to a file (written through a temporary name); returns bytes written.
  size_t Download(const std::string& path, const std::string& file) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Prints a one-line job summary ("<id> running 42% tiles 3/8 done ...").
std::string FormatStatusLine(const nlohmann::json& status_info);
// Polls the job (or follows its event stream) until it ends, drawing a progress bar on
// stderr; returns the final statusInfo. Bounded by timeout_s (0 = none).
nlohmann::json WaitForJob(const RemoteClient& client, const std::string& id, double poll_s,
                          double timeout_s, bool quiet);
// Exit code for a job's final status: 0 successful, kExitJobFailed otherwise.
int ExitCodeForStatus(const nlohmann::json& status_info);

}  // namespace satmesh::cli

namespace satmesh::cli {
// Runs a remote command body; a RemoteError is printed and becomes its exit code.
int RunRemote(const std::function<int()>& body);
}  // namespace satmesh::cli
