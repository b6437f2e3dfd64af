#include "server/api.h"

#include <httplib.h>
#include <sys/socket.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <regex>
#include <thread>

#include "core/common/error.h"
#include "core/tiling/memory_budget.h"
#include "proto/job_spec_json.h"
#include "server/api_documents.h"
#include "server/problem.h"
#include "server/redis_queue.h"

namespace satmesh::server {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

void MakeLinksAbsolute(const httplib::Request& req, json* body);

// Debian's httplib (0.11) listens with a backlog of 5 (CPPHTTPLIB_LISTEN_BACKLOG, compiled
// into the library): in a burst of new connections the rest wait for SYN retries (1 s,
// 3 s: p99 2.7 s for 500 concurrent status requests, RELIABILITY.md). listen() again on
// the bound socket raises it (Linux; capped by net.core.somaxconn).
struct HttpServer : httplib::Server {
  void RaiseListenBacklog(int backlog) { ::listen(svr_sock_, backlog); }
};

// JSON text of an answer. Strings from the request (a path in a 404's detail, a job's
// message naming a file) may hold invalid UTF-8, on which dump() throws: in httplib's error
// handler that terminated the server (GET /jobs/x%FF..., found by fuzz_http). Replaced
// by U+FFFD instead.
std::string Text(const json& body) { return body.dump(-1, ' ', false, json::error_handler_t::replace); }

void SendJson(const httplib::Request& req, httplib::Response& res, json body, int status = 200) {
  MakeLinksAbsolute(req, &body);
  res.status = status;
  res.set_content(Text(body), "application/json");
}

void SendProblem(httplib::Response& res, const Problem& p) {
  res.status = p.status;
  res.set_content(Text(p.body), "application/problem+json");
}

bool ConstantTimeEquals(const std::string& a, const std::string& b) {
  unsigned diff = unsigned(a.size() ^ b.size());
  for (size_t i = 0; i < a.size(); ++i) diff |= unsigned(a[i] ^ b[i % (b.empty() ? 1 : b.size())]);
  return diff == 0 && !b.empty();
}

std::string ContentType(const std::string& file) {
  const std::string ext = fs::path(file).extension().string();
  if (ext == ".glb") return "model/gltf-binary";
  if (ext == ".json") return "application/json";
  if (ext == ".tif") return "image/tiff";
  if (ext == ".png") return "image/png";
  return "application/octet-stream";
}

void SendFile(httplib::Response& res, const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  SATMESH_CHECK(in.good(), ErrorCode::kIo, "cannot read '" + path.filename().string() + "'");
  std::ostringstream data;
  data << in.rdbuf();
  res.set_content(data.str(), ContentType(path.string()));
}

// The methods each route answers (HEAD goes with GET; OPTIONS with every route): the one
// table behind 405 + Allow and the CORS preflight. Empty: no such route (404).
std::string AllowedMethods(const std::string& path) {
  static const std::regex get_only(
      R"(/|/conformance|/api|/health|/metrics|/processes|/processes/[^/]+|/jobs/[^/]+/(tiles|results|events|viewer|tileset\.json)|/jobs/[^/]+(/results)?/tiles/\d{1,6}_\d{1,6}\.glb|/jobs/[^/]+/results/[^/]+|/viewer/.+)");
  static const std::regex post(R"(/processes/[^/]+/execution)");
  static const std::regex get_delete(R"(/jobs/[^/]+)");
  if (std::regex_match(path, get_only) || path == "/jobs") return "GET, HEAD, OPTIONS";
  if (std::regex_match(path, post)) return "POST, OPTIONS";
  if (std::regex_match(path, get_delete)) return "GET, HEAD, DELETE, OPTIONS";
  return "";
}

// Pages a browser opens by navigating (no Authorization header): the viewer page (the
// same for every job; it sends the token itself) and CesiumJS.
bool IsPublicPage(const std::string& path) {
  static const std::regex viewer(R"(/jobs/[^/]+/viewer)");
  return path == "/health" || path.rfind("/viewer/", 0) == 0 || std::regex_match(path, viewer);
}

// Links of JSON documents as absolute URLs (OGC API clients such as OWSLib follow them
// as they are), from the request's Host (and X-Forwarded-Proto behind a proxy).
void MakeLinksAbsolute(const httplib::Request& req, json* body) {
  if (!req.has_header("Host")) return;
  const std::string proto = req.has_header("X-Forwarded-Proto") ? req.get_header_value("X-Forwarded-Proto") : "http";
  const std::string base = proto + "://" + req.get_header_value("Host");
  const std::function<void(json&)> visit = [&](json& j) {
    if (j.is_array()) {
      for (auto& e : j) visit(e);
    } else if (j.is_object()) {
      for (auto& [key, value] : j.items()) {
        if (key == "links" && value.is_array()) {
          for (auto& link : value)
            if (link.is_object() && link.contains("href") && link["href"].is_string() &&
                link["href"].get<std::string>().rfind("/", 0) == 0)
              link["href"] = base + link["href"].get<std::string>();
        } else if (key != "schema") {  // the process description's job schema: as it is
          visit(value);
        }
      }
    }
  };
  visit(*body);
}

[[noreturn]] void NoSuchJob(const std::string& id) {
  throw HttpError(404, "no-such-job", "no job with id '" + id + "'");
}

}  // namespace

std::string ServerOptions::Check() const {
  if (port < 0 || port > 65535) return "port: " + std::to_string(port) + " not in [0, 65535]";
  if (data_dir.empty()) return "data_dir: required";
  if (max_body_bytes < 1024) return "max_body_bytes: must be >= 1024";
  if (http_threads < 1 || http_threads > 1024) return "http_threads: not in [1, 1024]";
  if (max_stream_s < 1) return "max_stream_s: must be >= 1";
  for (const auto& origin : cors_origins) {
    const bool ok = origin == "*" || ((origin.rfind("http://", 0) == 0 || origin.rfind("https://", 0) == 0) &&
                                      origin.find('/', origin.find("//") + 2) == std::string::npos);
    if (!ok) return "cors_origins: '" + origin + "' is not '*' or an origin (scheme://host[:port], no path)";
  }
  if (!(memory_budget_mb >= 0)) return "memory_budget_mb: must be >= 0";
  if (!queue.empty()) {
    RedisQueueOptions q = redis;
    q.url = queue;
    const std::string p = q.Check();
    if (!p.empty()) return p;
    try {
      ParseRedisUrl(queue);
    } catch (const Error& e) {
      return e.what();
    }
  }
  std::string p = inputs.Check();
  if (!p.empty()) return p;
  return scheduler.Check();
}

struct ApiServer::Impl {
  ServerOptions options;
  JobExecutor* executor;
  JobStore store;
  std::unique_ptr<JobQueue> queue;  // the embedded Scheduler, or Redis (--queue)
  JobQueue& scheduler;
  HttpServer http;
  std::thread listener;
  json job_schema, openapi;
  std::string viewer_dir, viewer_page;

  Impl(const ServerOptions& o, JobExecutor* e)
      : options(o), executor(e), store(o.data_dir), queue(MakeQueue(o, &store, e)), scheduler(*queue) {}

  static std::unique_ptr<JobQueue> MakeQueue(const ServerOptions& o, JobStore* store, JobExecutor* e) {
    if (o.queue.empty()) return std::make_unique<Scheduler>(store, e, o.scheduler);
    RedisQueueOptions q = o.redis;
    q.url = o.queue;
    return std::make_unique<RedisJobQueue>(q, o.data_dir);
  }

  JobRecord RequireJob(const std::string& id) const {
    auto job = scheduler.Get(id);
    if (!job) NoSuchJob(id);
    return *job;
  }

  void Execute(const httplib::Request& req, httplib::Response& res) {
    const std::string type = req.get_header_value("Content-Type");
    if (!type.empty() && type.find("json") == std::string::npos)
      throw HttpError(415, "unsupported-media-type", "Content-Type must be application/json, got '" + type + "'");
    json body;
    try {
      body = json::parse(req.body);
    } catch (const json::parse_error& e) {
      throw HttpError(400, "invalid-json", std::string("request body: ") + e.what());
    }
    // OGC API - Processes: {"inputs": {"job": JOB}} as the process description declares;
    // also accepted: {"inputs": JOB} and JOB itself.
    json job = body.is_object() && body.contains("inputs") ? body["inputs"] : body;
    if (job.is_object() && job.size() == 1 && job.contains("job")) {
      job = json(job["job"]);
      if (!job.is_object()) throw HttpError(400, "bad-request", "inputs.job: must be an object (the job)");
    }
    if (job.is_object() && job.contains("images") && job["images"].is_array())
      CheckImageCount(job["images"].size(), options.inputs);
    ResolveHrefs(&job, options.inputs);
    // The server's budget per worker, unless the job names its own (kept in the record).
    if (job.is_object() && (!job.contains("tiling") || job["tiling"].is_object()) &&
        !job["tiling"].contains("memory_budget_mb"))
      job["tiling"]["memory_budget_mb"] = options.memory_budget_mb > 0
                                              ? options.memory_budget_mb
                                              : DefaultMemoryBudgetMb(options.scheduler.workers);
    JobSpec spec = proto::JobSpecFromJson(job, "/");
    spec.initial_mesh.max_faces = options.inputs.max_mesh_faces;
    const std::string problem = spec.Check();
    if (!problem.empty()) ThrowError(ErrorCode::kInvalidArgument, problem);
    CheckLimits(spec, {}, options.inputs);
    const ExecutionPlan plan = executor->Plan(spec);
    CheckLimits(spec, plan, options.inputs);
    const std::string key = req.get_header_value("Idempotency-Key");
    if (key.size() > 256) throw HttpError(400, "bad-request", "Idempotency-Key: longer than 256 characters");
    bool created = false;
    const JobRecord record = scheduler.Submit(job, spec, plan, key, &created);
    if (!created && record.request != job)
      throw HttpError(422, "idempotency-key-reused", "Idempotency-Key '" + key + "' was used for a different job");
    res.set_header("Location", "/jobs/" + record.id);
    res.set_header("Preference-Applied", "respond-async");
    SendJson(req, res, StatusInfo(record), created ? 201 : 200);
  }

  void Results(const httplib::Request& req, const std::string& id, httplib::Response& res) const {
    const JobRecord job = RequireJob(id);
    if (job.status == JobStatus::kAccepted || job.status == JobStatus::kRunning)
      throw HttpError(404, "result-not-ready", "job '" + id + "' is " + JobStatusName(job.status));
    if (job.status == JobStatus::kDismissed) throw HttpError(410, "job-dismissed", "job '" + id + "' was dismissed");
    if (job.status == JobStatus::kFailed) throw HttpError(422, "job-failed", "job '" + id + "' failed: " + job.message);
    const fs::path dir = scheduler.JobDir(id);
    const std::string base = "/jobs/" + id + "/results/";
    json links = json::array();
    json out = {{"jobID", id}};
    for (const char* file : {"tileset.json", "metrics.json", "mesh.ply", "dsm.tif", "preview.png", "convergence.png"}) {
      if (!fs::exists(dir / file)) continue;
      const std::string name = fs::path(file).stem().string();
      out[name] = {{"href", base + file}, {"type", ContentType(file)}};
      links.push_back({{"href", base + file}, {"rel", name}, {"type", ContentType(file)}});
    }
    if (fs::exists(dir / "metrics.json")) out["metrics"]["value"] = ReadJsonFile((dir / "metrics.json").string());
    out["tiles"] = TileList(job)["tiles"];
    out["links"] = links;
    SendJson(req, res, out);
  }

  void Stream(const std::string& id, httplib::Response& res) {
    RequireJob(id);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(options.max_stream_s);
    auto last = std::make_shared<uint64_t>(UINT64_MAX);
    res.set_header("Cache-Control", "no-cache");
    res.set_chunked_content_provider(
        "text/event-stream", [this, id, deadline, last](size_t, httplib::DataSink& sink) {
          if (*last != UINT64_MAX) *last = scheduler.WaitForChange(*last, 1000);
          else *last = scheduler.version();
          const auto job = scheduler.Get(id);
          if (!job) return false;
          const std::string event = "event: status\ndata: " + Text(StatusInfo(*job)) + "\n\n";
          if (!sink.write(event.data(), event.size())) return false;
          if (IsTerminal(job->status) || std::chrono::steady_clock::now() > deadline) sink.done();
          return true;
        });
  }

  void Routes() {
    http.Get("/", [](const auto& req, auto& res) { SendJson(req, res, LandingPage()); });
    http.Get("/conformance", [](const auto& req, auto& res) { SendJson(req, res, Conformance()); });
    http.Get("/api", [this](const auto& req, auto& res) { SendJson(req, res, openapi); });
    http.Get("/health", [this](const auto& req, auto& res) {
      const auto s = scheduler.Stats();
      // Queue mode: the workers seen in the last minute (any machine); else this process's.
      SendJson(req, res, {{"status", "ok"}, {"workers", s.workers_seen >= 0 ? s.workers_seen : options.scheduler.workers},
                     {"tiles_queued", s.tiles_queued}, {"tiles_running", s.tiles_running}});
    });
    http.Get("/metrics", [this](const auto& req, auto& res) {
      res.set_content(PrometheusText(scheduler.Stats()), "text/plain; version=0.0.4");
    });
    http.Get("/processes", [](const auto& req, auto& res) {
      SendJson(req, res, {{"processes", json::array({ProcessSummary()})},
                     {"links", json::array({{{"href", "/processes"}, {"rel", "self"}}})}});
    });
    http.Get(R"(/processes/([^/]+))", [this](const auto& req, auto& res) {
      if (req.matches[1] != kProcessId)
        throw HttpError(404, "no-such-process", "no process '" + std::string(req.matches[1]) + "'");
      SendJson(req, res, ProcessDescription(job_schema));
    });
    http.Post(R"(/processes/([^/]+)/execution)", [this](const auto& req, auto& res) {
      if (req.matches[1] != kProcessId)
        throw HttpError(404, "no-such-process", "no process '" + std::string(req.matches[1]) + "'");
      Execute(req, res);
    });
    http.Get("/jobs", [this](const auto& req, auto& res) {
      std::optional<JobStatus> status;
      if (req.has_param("status")) status = JobStatusFromName(req.get_param_value("status"));
      size_t limit = 100;
      if (req.has_param("limit")) {
        const std::string v = req.get_param_value("limit");
        if (v.empty() || v.size() > 6 || v.find_first_not_of("0123456789") != std::string::npos || std::stoul(v) < 1)
          throw HttpError(400, "bad-request", "limit: '" + v + "' is not an integer in [1, 999999]");
        limit = std::stoul(v);
      }
      json jobs = json::array();
      for (const auto& job : scheduler.List(status, limit)) jobs.push_back(StatusInfo(job));
      SendJson(req, res, {{"jobs", jobs}, {"links", json::array({{{"href", "/jobs"}, {"rel", "self"}}})}});
    });
    http.Get(R"(/jobs/([^/]+))", [this](const auto& req, auto& res) {
      SendJson(req, res, StatusInfo(RequireJob(req.matches[1])));
    });
    http.Delete(R"(/jobs/([^/]+))", [this](const auto& req, auto& res) {
      const auto job = scheduler.Dismiss(req.matches[1]);
      if (!job) NoSuchJob(req.matches[1]);
      SendJson(req, res, StatusInfo(*job));
    });
    http.Get(R"(/jobs/([^/]+)/tiles)", [this](const auto& req, auto& res) {
      SendJson(req, res, TileList(RequireJob(req.matches[1])));
    });
    http.Get(R"(/jobs/([^/]+)(?:/results)?/tiles/(\d{1,6})_(\d{1,6})\.glb)", [this](const auto& req, auto& res) {
      const JobRecord job = RequireJob(req.matches[1]);
      const TileKey key{std::stoi(req.matches[2]), std::stoi(req.matches[3])};
      for (const auto& t : job.tiles) {
        if (!(t.key == key)) continue;
        if (t.status != TileStatus::kDone || job.status == JobStatus::kDismissed)
          throw HttpError(404, "result-not-ready", "tile " + key.Name() + " is " + TileStatusName(t.status));
        return SendFile(res, fs::path(scheduler.JobDir(job.id)) / "tiles" / (key.Name() + ".glb"));
      }
      throw HttpError(404, "no-such-tile", "job '" + job.id + "' has no tile " + key.Name());
    });
    http.Get(R"(/jobs/([^/]+)/results)", [this](const auto& req, auto& res) { Results(req, req.matches[1], res); });
    http.Get(R"(/jobs/([^/]+)/results/(tileset\.json|metrics\.json|mesh\.ply|dsm\.tif|preview\.png|convergence\.png))",
             [this](const auto& req, auto& res) {
               const JobRecord job = RequireJob(req.matches[1]);
               if (job.status != JobStatus::kSuccessful)
                 throw HttpError(404, "result-not-ready", "job '" + job.id + "' is " + JobStatusName(job.status));
               const fs::path file = fs::path(scheduler.JobDir(job.id)) / std::string(req.matches[2]);
               if (!fs::exists(file)) throw HttpError(404, "not-found", "job '" + job.id + "' has no " + file.filename().string());
               SendFile(res, file);
             });
    http.Get(R"(/jobs/([^/]+)/events)", [this](const auto& req, auto& res) { Stream(req.matches[1], res); });
    http.Get(R"(/jobs/([^/]+)/tileset\.json)", [this](const auto& req, auto& res) {
      const JobRecord job = RequireJob(req.matches[1]);
      if (job.status == JobStatus::kDismissed) throw HttpError(410, "job-dismissed", "job '" + job.id + "' was dismissed");
      res.set_header("Cache-Control", "no-cache");
      SendJson(req, res, LiveTileset(job));
    });
    http.Get(R"(/jobs/([^/]+)/viewer)", [this](const auto& req, auto& res) {
      RequireJob(req.matches[1]);
      res.set_content(viewer_page, "text/html; charset=utf-8");
    });
    // CesiumJS's scripts as a JavaScript MIME type httplib does not compress: it would
    // Brotli-compress every request at quality 11 (Cesium.js: 11 s instead of 0.04 s).
    http.set_file_extension_and_mimetype_mapping("js", "application/x-javascript");
    SATMESH_CHECK(http.set_mount_point("/viewer/Cesium", viewer_dir + "/Cesium"), ErrorCode::kIo,
                  "viewer: cannot serve '" + viewer_dir + "/Cesium'");
  }

  // CORS: allowed origins get Access-Control-Allow-Origin on every answer; preflights
  // (OPTIONS with Access-Control-Request-Method) are answered here, before authentication.
  // Returns true when the request is answered.
  bool AnswerCorsAndMethods(const httplib::Request& req, httplib::Response& res) const {
    const std::string origin = req.get_header_value("Origin");
    bool allowed_origin = false;
    for (const auto& o : options.cors_origins) allowed_origin = allowed_origin || o == "*" || o == origin;
    if (!origin.empty() && allowed_origin) {
      const bool any = std::find(options.cors_origins.begin(), options.cors_origins.end(), "*") != options.cors_origins.end();
      res.set_header("Access-Control-Allow-Origin", any ? "*" : origin);
      if (!any) res.set_header("Vary", "Origin");
      res.set_header("Access-Control-Expose-Headers", "Location, Preference-Applied, Content-Length");
    }
    const std::string allow = AllowedMethods(req.path);
    if (allow.empty()) return false;  // 404 from the router
    if (req.method == "OPTIONS") {
      res.status = 204;
      res.set_header("Allow", allow);
      if (allowed_origin && req.has_header("Access-Control-Request-Method")) {
        res.set_header("Access-Control-Allow-Methods", allow);
        res.set_header("Access-Control-Allow-Headers",
                       "Authorization, Content-Type, Idempotency-Key, Prefer, Cache-Control, Last-Event-ID");
        res.set_header("Access-Control-Max-Age", "600");
      }
      return true;
    }
    const bool listed = (", " + allow + ",").find(", " + req.method + ",") != std::string::npos;
    if (listed) return false;
    res.set_header("Allow", allow);
    SendProblem(res, {405, {{"type", ProblemTypeUri("method-not-allowed")}, {"title", "Method Not Allowed"},
                            {"status", 405}, {"detail", req.method + " " + req.path + ": allowed: " + allow}}});
    return true;
  }

  void Hooks() {
    http.set_payload_max_length(options.max_body_bytes);
    // Pollers keep their connection (httplib's default closes it every 5 requests, and
    // reconnect bursts overflow its short listen backlog: 1 s SYN retries).
    http.set_keep_alive_max_count(1000);
    http.set_keep_alive_timeout(30);
    http.set_tcp_nodelay(true);  // no Nagle/delayed-ACK 40 ms stalls on kept-alive connections
    http.new_task_queue = [n = options.http_threads] { return new httplib::ThreadPool(size_t(n)); };
    http.set_exception_handler([](const httplib::Request& req, httplib::Response& res, std::exception_ptr error) {
      const Problem p = ProblemFromException(error);
      if (p.status >= 500) spdlog::error("{} {}: {}", req.method, req.path, p.body["detail"].get<std::string>());
      SendProblem(res, p);
    });
    http.set_error_handler(httplib::Server::HandlerWithResponse([](const httplib::Request& req, httplib::Response& res) {
      if (res.body.empty())
        SendProblem(res, ProblemForStatus(res.status, req.method + " " + req.path + ": HTTP " + std::to_string(res.status)));
      return httplib::Server::HandlerResponse::Handled;
    }));
    http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      // httplib decodes %00 into the path; a file name would end there ("Cesium.js%00.html"
      // would serve Cesium.js as text/html). No route has a NUL: refused before any.
      if (req.path.find('\0') != std::string::npos) {
        SendProblem(res, ProblemForStatus(400, "the request path contains a NUL byte (%00)"));
        return httplib::Server::HandlerResponse::Handled;
      }
      if (AnswerCorsAndMethods(req, res)) return httplib::Server::HandlerResponse::Handled;
      if (options.token.empty() || IsPublicPage(req.path)) return httplib::Server::HandlerResponse::Unhandled;
      const std::string auth = req.get_header_value("Authorization");
      const std::string prefix = "Bearer ";
      if (auth.rfind(prefix, 0) == 0 && ConstantTimeEquals(auth.substr(prefix.size()), options.token))
        return httplib::Server::HandlerResponse::Unhandled;
      res.set_header("WWW-Authenticate", "Bearer");
      SendProblem(res, {401, {{"type", ProblemTypeUri("unauthorized")}, {"title", "Unauthorized"},
                              {"status", 401}, {"detail", "a valid bearer token is required"}}});
      return httplib::Server::HandlerResponse::Handled;
    });
  }
};

ApiServer::ApiServer(const ServerOptions& options, JobExecutor* executor)
    : impl_(std::make_unique<Impl>(options, executor)) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "server options: " + problem);
  const std::string proto = options.proto_dir.empty() ? SATMESH_PROTO_DIR : options.proto_dir;
  impl_->job_schema = ReadJsonFile(proto + "/job.schema.json");
  impl_->openapi = ReadJsonFile(proto + "/openapi.json");
  impl_->viewer_dir = options.viewer_dir.empty() ? SATMESH_VIEWER_DIR : options.viewer_dir;
  std::ifstream page(impl_->viewer_dir + "/viewer.html");
  SATMESH_CHECK(page.good() && fs::exists(impl_->viewer_dir + "/Cesium/Cesium.js"), ErrorCode::kNotFound,
                "viewer_dir: '" + impl_->viewer_dir + "' has no viewer.html and Cesium/Cesium.js");
  std::ostringstream text;
  text << page.rdbuf();
  impl_->viewer_page = text.str();
}

ApiServer::~ApiServer() { Stop(); }

int ApiServer::Start() {
  impl_->Routes();
  impl_->Hooks();
  impl_->scheduler.Start();
  const auto& o = impl_->options;
  const int port = o.port == 0 ? impl_->http.bind_to_any_port(o.host) : (impl_->http.bind_to_port(o.host, o.port) ? o.port : -1);
  if (port < 0) {
    impl_->scheduler.Stop();
    ThrowError(ErrorCode::kIo, "cannot listen on " + o.host + ":" + std::to_string(o.port));
  }
  impl_->http.RaiseListenBacklog(1024);
  impl_->listener = std::thread([this] { impl_->http.listen_after_bind(); });
  if (o.queue.empty())
    spdlog::info("satmesh-server listening on http://{}:{} (data: {}, {} worker(s))", o.host, port,
                 o.data_dir, o.scheduler.workers);
  else
    spdlog::info("satmesh-server listening on http://{}:{} (data: {}, API node of queue {})", o.host, port,
                 o.data_dir, o.queue);
  return port;
}

void ApiServer::Stop() {
  impl_->http.stop();
  if (impl_->listener.joinable()) impl_->listener.join();
  impl_->scheduler.Stop();
}

}  // namespace satmesh::server
