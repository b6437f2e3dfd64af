// Units without HTTP: problem mapping, href policy, store round trip.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "core/common/error.h"
#include "server/inputs.h"
#include "server/plan_cache.h"
#include "server/problem.h"
#include "server/store.h"
#include "tests/server/test_server.h"

namespace satmesh::server {
namespace {

int StatusOf(const std::function<void()>& f) {
  try {
    f();
  } catch (...) {
    return ProblemFromException(std::current_exception()).status;
  }
  return 0;
}

TEST(PlanCache, MakesAJobsPlanOnceAndDropsTheLeastRecentlyUsed) {
  PlanCache cache(2);
  int made = 0;
  const auto make = [&made](int nx) {
    return [&made, nx] {
      ++made;
      JobPlan plan;
      plan.nx = nx;
      return plan;
    };
  };
  const auto a = cache.Get("jobs/a", make(1));
  EXPECT_EQ(cache.Get("jobs/a", make(99)), a);  // the same plan, not made again
  EXPECT_EQ(made, 1);
  EXPECT_EQ(a->nx, 1);
  cache.Get("jobs/b", make(2));
  cache.Get("jobs/a", make(99));  // a is the most recent again
  cache.Get("jobs/c", make(3));   // drops b
  EXPECT_EQ(made, 3);
  EXPECT_EQ(cache.Get("jobs/a", make(99))->nx, 1);
  EXPECT_EQ(cache.Get("jobs/b", make(4))->nx, 4);  // made again
  EXPECT_EQ(made, 4);
  EXPECT_EQ(a->nx, 1);  // a plan handed out stays valid whatever is dropped
  // A failed plan caches nothing.
  EXPECT_THROW(cache.Get("jobs/d", [] () -> JobPlan { ThrowError(ErrorCode::kInvalidInput, "bad"); }),
               Error);
  EXPECT_EQ(cache.Get("jobs/d", make(5))->nx, 5);
}

TEST(ProblemFromException, MapsErrorCodesToHttpStatus) {
  EXPECT_EQ(StatusOf([] { ThrowError(ErrorCode::kInvalidArgument, "x"); }), 400);
  EXPECT_EQ(StatusOf([] { ThrowError(ErrorCode::kInvalidInput, "x"); }), 422);
  EXPECT_EQ(StatusOf([] { ThrowError(ErrorCode::kNotFound, "x"); }), 404);
  EXPECT_EQ(StatusOf([] { ThrowError(ErrorCode::kCancelled, "x"); }), 409);
  EXPECT_EQ(StatusOf([] { ThrowError(ErrorCode::kIo, "x"); }), 500);
  EXPECT_EQ(StatusOf([] { throw HttpError(410, "gone", "x"); }), 410);
  EXPECT_EQ(StatusOf([] { throw std::runtime_error("x"); }), 500);
  try {
    throw HttpError(404, "no-such-job", "no job 'q'");
  } catch (...) {
    const Problem p = ProblemFromException(std::current_exception());
    EXPECT_EQ(p.body["type"], "http://www.opengis.net/def/exceptions/ogcapi-processes-1/1.0/no-such-job");
    EXPECT_EQ(p.body["detail"], "no job 'q'");
  }
}

TEST(ResolveHrefs, RelativeUnderRootSymlinkEscapeAndVirtualPaths) {
  const std::string dir = testing::TempDir("hrefs");
  std::filesystem::create_directories(dir + "/root/in");
  std::ofstream(dir + "/root/in/a.tif") << "a";
  std::ofstream(dir + "/outside.tif") << "o";
  std::filesystem::create_symlink(dir + "/outside.tif", dir + "/root/link.tif");
  InputPolicy policy;
  policy.data_roots = {dir + "/root"};
  policy.allowed_vsi = {"/vsicurl/https://data.example.com/"};
  auto job = [](const std::string& href) {
    return nlohmann::json{{"images", {{{"href", href}}}}, {"initial", {{"dsm", href}}}};
  };
  nlohmann::json ok = job("in/a.tif");
  ResolveHrefs(&ok, policy);
  EXPECT_EQ(ok["images"][0]["href"], std::filesystem::canonical(dir + "/root/in/a.tif").string());
  nlohmann::json vsi = job("/vsicurl/https://data.example.com/x.tif");
  ResolveHrefs(&vsi, policy);
  EXPECT_EQ(vsi["initial"]["dsm"], "/vsicurl/https://data.example.com/x.tif");
  for (const std::string& bad : std::vector<std::string>{"link.tif", "../outside.tif", dir + "/outside.tif",
                                 "/vsicurl/https://evil.example.com/x.tif", "/vsis3/b/x.tif"}) {
    nlohmann::json j = job(bad);
    EXPECT_EQ(StatusOf([&] { ResolveHrefs(&j, policy); }), 403) << bad;
  }
  nlohmann::json missing = job("in/none.tif");
  EXPECT_EQ(StatusOf([&] { ResolveHrefs(&missing, policy); }), 400);
}

// The security review of paths from requests (RELIABILITY.md): each hostile href is
// refused with the status and reason given, and none reaches GDAL or a file outside.
TEST(ResolveHrefs, HostileHrefsAreRefusedWithTheReason) {
  namespace fs = std::filesystem;
  const std::string dir = testing::TempDir("hostile");
  fs::create_directories(dir + "/root/in");
  fs::create_directories(dir + "/root2");
  std::ofstream(dir + "/root/in/a.tif") << "a";
  std::ofstream(dir + "/root2/a.tif") << "a";
  std::ofstream(dir + "/root/in/etc.vrt")
      << "<VRTDataset rasterXSize=\"1\" rasterYSize=\"1\"><VRTRasterBand dataType=\"Byte\" band=\"1\">"
         "<SimpleSource><SourceFilename>/etc/passwd</SourceFilename></SimpleSource></VRTRasterBand></VRTDataset>";
  ASSERT_EQ(::mkfifo((dir + "/root/in/fifo.tif").c_str(), 0600), 0);  // GDAL would block on it
  InputPolicy policy;
  policy.data_roots = {dir + "/root"};
  policy.allowed_vsi = {"/vsicurl/https://data.example.com/pub/"};
  struct Case {
    std::string href;
    int status;
    std::string reason;
  };
  const std::vector<Case> cases = {
      {std::string("in/a.tif\0.png", 13), 403, "contains a NUL byte"},
      {"in/../../root2/a.tif", 403, "'..' is not allowed"},
      {dir + "/root2/a.tif", 403, "outside the server's data roots"},  // a sibling sharing the root's prefix
      {"%2e%2e/root2/a.tif", 400, "does not exist"},  // no URL decoding of local paths: a literal name
      {"/vsicurl/https://data.example.com/pub/%2E%2e/private/x.tif", 403, "encoded dots, slashes or backslashes"},
      {"/vsicurl/https://data.example.com/pub/..%2fprivate/x.tif", 403, "encoded dots, slashes or backslashes"},
      {"/vsicurl/https://data.example.com/pub/..%5Cprivate/x.tif", 403, "encoded dots, slashes or backslashes"},
      {"/vsicurl/https://data.example.com/pub/..\\private/x.tif", 403, "encoded dots, slashes or backslashes"},
      {"/vsicurl/https://data.example.com/pub/../private/x.tif", 403, "'..' is not allowed"},
      {"/vsicurl/https://data.example.com/private/x.tif", 403, "is not allowed by this server"},
      {"/vsicurl?url=https://data.example.com/pub/x.tif", 403, "is not allowed by this server"},
      {"/vsimem/x.tif", 403, "is not allowed by this server"},
      {"/vsistdin/", 403, "is not allowed by this server"},
      {"/vsizip//vsicurl/https://data.example.com/pub/x.zip/a.tif", 403, "is not allowed by this server"},
      {"in/etc.vrt", 403, "is a VRT file; inputs must be a self-contained raster format"},
      {"in/fifo.tif", 400, "is not a file"},
      {".", 400, "is not a file"},
  };
  for (const Case& k : cases) {
    nlohmann::json job{{"images", {{{"href", k.href}}}}};
    int status = 0;
    std::string detail;
    try {
      ResolveHrefs(&job, policy);
    } catch (...) {
      const Problem p = ProblemFromException(std::current_exception());
      status = p.status;
      detail = p.body.value("detail", "");
    }
    EXPECT_EQ(status, k.status) << k.href << ": " << detail;
    EXPECT_NE(detail.find(k.reason), std::string::npos) << k.href << ": " << detail;
    EXPECT_EQ(detail.rfind("images[0].href: ", 0), 0u) << detail;
  }
  policy.allowed_vsi = {"/vsicurl/https://data.example.com"};  // would also allow data.example.com.evil
  EXPECT_NE(policy.Check().find("must start with /vsi and end with '/'"), std::string::npos) << policy.Check();
}

TEST(JobStore, StateRoundTripAndRunningTilesReload) {
  JobStore store(testing::TempDir("store"));
  JobRecord job;
  job.id = "j1";
  job.request = {{"images", 1}};
  job.status = JobStatus::kRunning;
  job.created = NowRfc3339();
  job.tiles.resize(2);
  job.tiles[0].status = TileStatus::kDone;
  job.tiles[0].duration_s = 1.5;
  job.tiles[1].key = {1, 0};
  job.tiles[1].status = TileStatus::kRunning;
  store.SaveRequest(job);
  store.SaveState(job);
  const auto all = store.LoadAll();
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].status, JobStatus::kRunning);
  EXPECT_EQ(all[0].request, job.request);
  EXPECT_EQ(all[0].tiles[1].key, (TileKey{1, 0}));
  EXPECT_EQ(all[0].tiles[1].status, TileStatus::kRunning);  // the scheduler re-queues it
  EXPECT_DOUBLE_EQ(all[0].tiles[0].duration_s, 1.5);
  EXPECT_FALSE(std::filesystem::exists(store.JobDir("j1") + "/state.json.tmp"));
}

TEST(ServerOptions, DefaultsAreValidAndBadValuesNamed) {
  ServerOptions o;
  EXPECT_EQ(o.Check(), "");
  o.scheduler.workers = 0;
  EXPECT_NE(o.Check().find("workers"), std::string::npos);
  o = {};
  o.max_body_bytes = 10;
  EXPECT_NE(o.Check().find("max_body_bytes"), std::string::npos);
}

}  // namespace
}  // namespace satmesh::server
