#include "server/store.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cerrno>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <fcntl.h>

#include "core/common/error.h"

namespace satmesh::server {
namespace fs = std::filesystem;
namespace {

constexpr const char* kJobNames[] = {"accepted", "running", "successful", "failed", "dismissed"};
constexpr const char* kTileNames[] = {"queued", "running", "done", "failed", "cancelled"};

// Writes path.tmp, flushes it to disk, renames it over path: readers see the old or the
// new file, never a partial one.
void WriteAtomic(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) ThrowIoError("cannot write '" + tmp.string() + "'", errno);
  size_t written = 0;
  int error = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = n < 0 ? errno : ENOSPC;
      break;
    }
    written += size_t(n);
  }
  if (error == 0 && ::fsync(fd) != 0) error = errno;
  ::close(fd);
  if (error != 0) {  // the previous file stays whole; no partial .tmp is left behind
    ::unlink(tmp.c_str());
    ThrowIoError("cannot write '" + tmp.string() + "'", error);
  }
  fs::rename(tmp, path);
}

nlohmann::json ReadJson(const fs::path& path) {
  std::ifstream in(path);
  SATMESH_CHECK(in.good(), ErrorCode::kNotFound, "cannot open '" + path.string() + "'");
  return nlohmann::json::parse(in);
}

}  // namespace

const char* JobStatusName(JobStatus s) { return kJobNames[int(s)]; }
const char* TileStatusName(TileStatus s) { return kTileNames[int(s)]; }
bool IsTerminal(JobStatus s) {
  return s == JobStatus::kSuccessful || s == JobStatus::kFailed || s == JobStatus::kDismissed;
}

JobStatus JobStatusFromName(const std::string& name) {
  for (int i = 0; i < 5; ++i)
    if (name == kJobNames[i]) return JobStatus(i);
  ThrowError(ErrorCode::kInvalidArgument,
             "status: '" + name + "' is not one of accepted, running, successful, failed, dismissed");
}

std::string NowRfc3339() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const int ms = int(std::chrono::duration_cast<std::chrono::milliseconds>(
                         now.time_since_epoch()).count() % 1000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, ms);
  return buf;
}

nlohmann::json StateToJson(const JobRecord& job) {
  nlohmann::json tiles = nlohmann::json::array();
  for (const auto& t : job.tiles) {
    tiles.push_back({{"x", t.key.x}, {"y", t.key.y}, {"status", TileStatusName(t.status)},
                     {"duration_s", t.duration_s}, {"attempts", t.attempts},
                     {"message", t.message}, {"result", t.result}});
  }
  return {{"id", job.id}, {"idempotency_key", job.idempotency_key},
          {"status", JobStatusName(job.status)}, {"created", job.created},
          {"started", job.started}, {"finished", job.finished}, {"updated", job.updated},
          {"message", job.message}, {"assembled", job.assembled}, {"pixels", job.pixels},
          {"tiles", tiles}};
}

JobRecord StateFromJson(const nlohmann::json& s) {
  JobRecord job;
  job.id = s.at("id");
  job.idempotency_key = s.value("idempotency_key", "");
  job.status = JobStatusFromName(s.at("status"));
  job.created = s.value("created", "");
  job.started = s.value("started", "");
  job.finished = s.value("finished", "");
  job.updated = s.value("updated", "");
  job.message = s.value("message", "");
  job.assembled = s.value("assembled", false);
  job.pixels = s.value("pixels", int64_t{0});
  for (const auto& t : s.at("tiles")) {
    TileRecord tile;
    tile.key = {t.at("x"), t.at("y")};
    const std::string status = t.at("status");
    for (int i = 0; i < 5; ++i)
      if (status == kTileNames[i]) tile.status = TileStatus(i);
    tile.duration_s = t.value("duration_s", 0.0);
    tile.attempts = t.value("attempts", 0);
    tile.message = t.value("message", "");
    if (t.contains("result")) tile.result = t["result"];
    tile.progress = tile.status == TileStatus::kDone ? 1.0 : 0.0;
    job.tiles.push_back(tile);
  }
  return job;
}

JobStore::JobStore(std::string data_dir) : jobs_dir_((fs::path(data_dir) / "jobs").string()) {
  fs::create_directories(jobs_dir_);
}

std::string JobStore::JobDir(const std::string& id) const {
  return (fs::path(jobs_dir_) / id).string();
}

void JobStore::SaveRequest(const JobRecord& job) const {
  fs::create_directories(fs::path(JobDir(job.id)) / "tiles");
  WriteAtomic(fs::path(JobDir(job.id)) / "job.json", job.request.dump(2));
}

void JobStore::SaveState(const JobRecord& job) const {
  WriteAtomic(fs::path(JobDir(job.id)) / "state.json", StateToJson(job).dump(1, ' ', false, nlohmann::json::error_handler_t::replace));
}

std::vector<JobRecord> JobStore::LoadAll() const {
  std::vector<JobRecord> jobs;
  for (const auto& entry : fs::directory_iterator(jobs_dir_)) {
    if (!entry.is_directory()) continue;
    try {
      JobRecord job = StateFromJson(ReadJson(entry.path() / "state.json"));
      job.request = ReadJson(entry.path() / "job.json");
      jobs.push_back(std::move(job));
    } catch (const std::exception& e) {
      spdlog::warn("job store: skipping '{}': {}", entry.path().string(), e.what());
    }
  }
  return jobs;
}

void JobStore::RemoveOutputs(const std::string& id) const {
  const fs::path dir = JobDir(id);
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name != "job.json" && name != "state.json") fs::remove_all(entry.path(), ec);
  }
}

}  // namespace satmesh::server
