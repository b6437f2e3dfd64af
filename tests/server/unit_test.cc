// Units without HTTP: problem mapping, href policy, store round trip.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/common/error.h"
#include "server/inputs.h"
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
