// libFuzzer target: the HTTP routes' path and query handling of a real ApiServer (stub
// engine, one finished job, a token) on loopback. The input is split at the first
// newline: the first line is the request target (sent as raw bytes: encoded dots,
// slashes, NULs and all), the rest the body; the first byte picks the method. Any answer
// of 500 or above, or no well-formed answer, is a finding (a crash in a handler thread
// aborts the process).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <thread>

#include "server/api.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/server/stub_executor.h"

namespace {

using namespace satmesh::server;
std::unique_ptr<testing::StubExecutor> executor;
std::unique_ptr<ApiServer> server;
int port = 0;
std::string job_id;

// One request over a fresh connection; returns the raw answer ("" when none).
std::string Exchange(const std::string& request) {
  const bool head = request.rfind("HEAD ", 0) == 0;  // headers only: no body follows
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(uint16_t(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  timeval timeout{10, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  // Closed with a reset, not into TIME_WAIT: tens of thousands of connections a minute
  // would use up the ephemeral ports and the next connect() would fail (EADDRNOTAVAIL).
  const linger reset{1, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_LINGER, &reset, sizeof(reset));
  std::string answer;
  int connected = ::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr));
  if (connected != 0 && errno == EINTR) {  // the connection goes on: wait until writable
    pollfd p{fd, POLLOUT, 0};
    while (::poll(&p, 1, 10000) < 0 && errno == EINTR) {
    }
    int error = 0;
    socklen_t length = sizeof(error);
    ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length);
    connected = error == 0 && (p.revents & POLLOUT) ? 0 : -1;
  }
  ssize_t sent = 0;
  while (connected == 0 && sent < ssize_t(request.size())) {
    const ssize_t n = ::send(fd, request.data() + sent, request.size() - size_t(sent), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    sent += n;
  }
  if (connected == 0 && sent == ssize_t(request.size())) {
    char buffer[65536];
    // (EINTR: libFuzzer's -timeout alarm fires every second and interrupts recv; taken
    // for "no answer" it made every long run fail after a while.)
    for (ssize_t n; (n = ::recv(fd, buffer, sizeof(buffer), 0)) > 0 || (n < 0 && errno == EINTR);) {
      if (n < 0) continue;
      answer.append(buffer, size_t(n));
      // Done when the body announced by Content-Length is in (httplib may keep the
      // connection open after some error answers despite "Connection: close").
      const size_t end = answer.find("\r\n\r\n");
      const size_t length_at = answer.find("Content-Length: ");
      if (end != std::string::npos && head) break;
      if (end != std::string::npos && length_at != std::string::npos && length_at < end &&
          answer.size() >= end + 4 + std::strtoul(answer.c_str() + length_at + 16, nullptr, 10))
        break;
    }
  }
  ::close(fd);
  return answer;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("satmesh_fuzz_http_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "root");
  ServerOptions options;
  options.port = 0;
  options.data_dir = (dir / "data").string();
  options.inputs.data_roots = {(dir / "root").string()};
  options.scheduler.workers = 1;
  options.http_threads = 4;
  options.token = "fuzz-token";
  executor = std::make_unique<testing::StubExecutor>(testing::Stub(1, 1, 0));
  server = std::make_unique<ApiServer>(options, executor.get());
  port = server->Start();
  std::atexit([] { server->Stop(); });  // before any static object is destroyed
  const std::string job = testing::MakeStubJob(options.inputs.data_roots[0]).dump();
  const std::string answer = Exchange("POST /processes/refine-mesh/execution HTTP/1.1\r\nHost: f\r\n"
                                      "Authorization: Bearer fuzz-token\r\nContent-Type: application/json\r\n"
                                      "Connection: close\r\nContent-Length: " + std::to_string(job.size()) + "\r\n\r\n" + job);
  const size_t at = answer.find("\"jobID\":\"");
  if (at == std::string::npos) satmesh::fuzz::Fail("the seed job was not accepted: " + answer);
  job_id = answer.substr(at + 9, answer.find('"', at + 9) - at - 9);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the one-tile job finishes
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* kMethods[] = {"GET", "GET", "GET", "DELETE", "POST", "OPTIONS", "HEAD", "PUT"};
  const std::string method = kMethods[data[0] % 8];
  const bool authorised = data[0] & 0x80;
  std::string rest(reinterpret_cast<const char*>(data + 1), size - 1);
  const size_t newline = rest.find('\n');
  std::string target = rest.substr(0, newline);
  const std::string body = newline == std::string::npos ? "" : rest.substr(newline + 1);
  // "{job}" stands for the finished job's id, so the job routes are reached.
  for (size_t at; (at = target.find("{job}")) != std::string::npos;) target.replace(at, 5, job_id);
  for (char& c : target)
    if (c == '\r' || c == ' ') c = '_';  // one request line; httplib answers 400 to a space
  if (target.empty() || target[0] != '/') target = "/" + target;
  // One Idempotency-Key for all: the body is parsed, checked and planned as before, but
  // at most one fuzzed job is created (thousands of accepted jobs slowed the stub server
  // past the answer timeout after ~12,000 requests).
  std::string request = method + " " + target + " HTTP/1.1\r\nHost: fuzz\r\nConnection: close\r\n"
                        "Idempotency-Key: fuzz\r\n";
  if (authorised) request += "Authorization: Bearer fuzz-token\r\n";
  // Always a length: without one httplib waits out its 5 s read timeout for a POST body
  // (a fuzzing speed of 2 requests a second).
  if (!body.empty()) request += "Content-Type: application/json\r\n";
  request += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  request += "\r\n" + body;
  const std::string answer = Exchange(request);
  if (answer.rfind("HTTP/1.1 ", 0) != 0)
    satmesh::fuzz::Fail("no HTTP answer (" + std::string(std::strerror(errno)) + ") to: " + request.substr(0, 200));
  const int status = std::atoi(answer.c_str() + 9);
  if (status >= 500) satmesh::fuzz::Fail("HTTP " + std::to_string(status) + " for: " + request.substr(0, 300) + "\n" + answer.substr(0, 600));
  return 0;
}
