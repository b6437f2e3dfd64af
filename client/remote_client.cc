#include "client/remote_client.h"

#include <httplib.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

namespace satmesh::cli {
namespace {

int ExitCodeForHttp(int status) {
  if (status == 401 || status == 403) return kExitAuth;
  if (status == 404 || status == 410) return kExitNotFound;
  return status < 500 ? kExitRejected : kExitFailure;
}

std::string Describe(const httplib::Result& r, const std::string& what) {
  std::string detail = r->body;
  try {
    const auto p = nlohmann::json::parse(r->body);
    if (p.contains("detail")) detail = p["detail"];
  } catch (const std::exception&) {
  }
  return what + ": HTTP " + std::to_string(r->status) + (detail.empty() ? "" : ": " + detail);
}

}  // namespace

struct RemoteClient::Impl {
  std::string server;
  httplib::Client http;
  Impl(const std::string& s, const std::string& token) : server(s), http(s) {
    http.set_connection_timeout(5, 0);
    http.set_read_timeout(60, 0);
    http.set_keep_alive(true);
    http.set_tcp_nodelay(true);
    if (!token.empty()) http.set_bearer_token_auth(token);
  }
  void Check(const httplib::Result& r, const std::string& what, bool allow_error) const {
    if (!r)
      throw RemoteError(kExitUnreachable, what + ": no answer from " + server + " (" + httplib::to_string(r.error()) + ")");
    if (!allow_error && r->status >= 400) throw RemoteError(ExitCodeForHttp(r->status), Describe(r, what));
  }
  static RemoteResponse From(const httplib::Result& r) {
    return {r->status, r->body, r->get_header_value("Content-Type"), r->get_header_value("Location")};
  }
};

nlohmann::json RemoteResponse::Json() const {
  try {
    return nlohmann::json::parse(body);
  } catch (const std::exception& e) {
    throw RemoteError(kExitFailure, std::string("the server answered something that is not JSON: ") + e.what());
  }
}

RemoteClient::RemoteClient(const std::string& server, const std::string& token) {
  const std::string url = server.empty() ? "http://127.0.0.1:8080" : server;
  if (url.rfind("http://", 0) != 0 && url.rfind("https://", 0) != 0)
    throw RemoteError(kExitUsage, "--server: expected http://host:port, got '" + url + "'");
  impl_ = std::make_unique<Impl>(url, token);
}
RemoteClient::~RemoteClient() = default;
RemoteClient::RemoteClient(RemoteClient&&) noexcept = default;

RemoteClient RemoteClient::FromArgs(const Args& args) {
  const char* env_server = std::getenv("SATMESH_SERVER");
  const char* env_token = std::getenv("SATMESH_TOKEN");
  return RemoteClient(args.GetOr("server", env_server ? env_server : ""),
                      args.GetOr("token", env_token ? env_token : ""));
}

RemoteResponse RemoteClient::Get(const std::string& path, bool allow_error) const {
  auto r = impl_->http.Get(path.c_str());
  impl_->Check(r, "GET " + path, allow_error);
  return Impl::From(r);
}

RemoteResponse RemoteClient::Post(const std::string& path, const std::string& json_body,
                                  const std::string& idempotency_key) const {
  httplib::Headers headers = {{"Prefer", "respond-async"}};
  if (!idempotency_key.empty()) headers.emplace("Idempotency-Key", idempotency_key);
  auto r = impl_->http.Post(path.c_str(), headers, json_body, "application/json");
  impl_->Check(r, "POST " + path, false);
  return Impl::From(r);
}

RemoteResponse RemoteClient::Delete(const std::string& path) const {
  auto r = impl_->http.Delete(path.c_str());
  impl_->Check(r, "DELETE " + path, false);
  return Impl::From(r);
}

size_t RemoteClient::Download(const std::string& path, const std::string& file) const {
  const std::string tmp = file + ".part";
  std::ofstream out(tmp, std::ios::binary);
  if (!out) throw RemoteError(kExitFailure, "cannot write '" + tmp + "'");
  size_t bytes = 0;
  int status = 0;
  auto r = impl_->http.Get(
      path.c_str(), [&](const httplib::Response& res) { status = res.status; return true; },
      [&](const char* data, size_t n) {
        if (status >= 400) return true;  // the problem body is read into nothing
        out.write(data, std::streamsize(n));
        bytes += n;
        return out.good();
      });
  out.close();
  if (!r || r->status >= 400) {
    std::filesystem::remove(tmp);
    impl_->Check(r, "GET " + path, false);
  }
  std::filesystem::rename(tmp, file);
  return bytes;
}

std::string FormatStatusLine(const nlohmann::json& s) {
  const auto& t = s["tiles"];
  char buf[512];
  std::snprintf(buf, sizeof buf, "%s  %-10s %3d%%  tiles %d/%d done, %d running, %d failed  %s",
                s.value("jobID", "?").c_str(), s.value("status", "?").c_str(), s.value("progress", 0),
                t.value("done", 0), t.value("total", 0), t.value("running", 0), t.value("failed", 0),
                s.value("message", "").c_str());
  return buf;
}

nlohmann::json WaitForJob(const RemoteClient& client, const std::string& id, double poll_s,
                          double timeout_s, bool quiet) {
  const auto start = std::chrono::steady_clock::now();
  nlohmann::json info;
  while (true) {
    info = client.Get("/jobs/" + id).Json();
    const std::string status = info.value("status", "");
    if (!quiet) {
      const int pct = info.value("progress", 0), width = 30;
      std::string bar(size_t(width * pct / 100), '#');
      bar.resize(width, '.');
      std::fprintf(stderr, "\r[%s] %3d%% %-10s tiles %d/%d", bar.c_str(), pct, status.c_str(),
                   info["tiles"].value("done", 0), info["tiles"].value("total", 0));
    }
    if (status == "successful" || status == "failed" || status == "dismissed") break;
    const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (timeout_s > 0 && waited > timeout_s) {
      if (!quiet) std::fprintf(stderr, "\n");
      throw RemoteError(kExitFailure, "job " + id + " still " + status + " after " + std::to_string(int(timeout_s)) + " s");
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(poll_s));
  }
  if (!quiet) std::fprintf(stderr, "\n");
  return info;
}

int ExitCodeForStatus(const nlohmann::json& s) {
  return s.value("status", "") == "successful" ? kExitOk : kExitJobFailed;
}

int RunRemote(const std::function<int()>& body) {
  try {
    return body();
  } catch (const RemoteError& e) {
    spdlog::error("{}", e.what());
    return e.exit_code();
  }
}

}  // namespace satmesh::cli
