// Malformed requests: each gets the right 4xx as problem+json naming the field, and the
// server stays healthy.
#include <gtest/gtest.h>

#include <filesystem>

#include "tests/server/test_server.h"

namespace satmesh::server::testing {
namespace {

using nlohmann::json;

struct Case {
  std::string method, path, body;
  int status;
  std::string detail;  // a substring the problem's detail must contain
  std::string content_type = "application/json";
};

json Job() { return {{"images", {{{"href", "a.tif"}}, {{"href", "b.tif"}}}}, {"initial", {{"dsm", "dsm.tif"}}}}; }

std::string With(const std::function<void(json&)>& edit) {
  json j = Job();
  edit(j);
  return j.dump();
}

std::vector<Case> Cases(const std::string& job_id) {
  const std::string exec = "/processes/refine-mesh/execution";
  std::vector<Case> c = {
      {"POST", exec, "{bad", 400, "request body"},
      {"POST", exec, "", 400, "request body"},
      {"POST", exec, "[]", 400, "job"},
      {"POST", exec, "\"x\"", 400, "job"},
      {"POST", exec, "null", 400, "job"},
      {"POST", exec, With([](json& j) { j.erase("images"); }), 400, "images"},
      {"POST", exec, With([](json& j) { j["images"] = "a.tif"; }), 400, "images"},
      {"POST", exec, With([](json& j) { j["images"].erase(1); }), 400, "images"},
      {"POST", exec, With([](json& j) { j["images"][0] = 5; }), 400, "images[0]"},
      {"POST", exec, With([](json& j) { j["images"][1].erase("href"); }), 400, "images[1].href"},
      {"POST", exec, With([](json& j) { j["images"][1]["href"] = 5; }), 400, "images[1].href"},
      {"POST", exec, With([](json& j) { j["images"][0]["href"] = ""; }), 400, "images[0].href"},
      {"POST", exec, With([](json& j) { j["images"][0]["href"] = true; }), 400, "images[0].href"},
      {"POST", exec, With([](json& j) { j["images"][0]["bias"] = {1}; }), 400, "images[0].bias"},
      {"POST", exec, With([](json& j) { j["images"][0]["bias"] = {"a", "b"}; }), 400, "images[0].bias[0]"},
      {"POST", exec, With([](json& j) { j.erase("initial"); }), 400, "initial"},
      {"POST", exec, With([](json& j) { j["initial"] = "dsm.tif"; }), 400, "initial"},
      {"POST", exec, With([](json& j) { j["initial"].erase("dsm"); }), 400, "initial: needs dsm or mesh"},
      {"POST", exec, With([](json& j) { j["initial"]["mesh"] = 1; }), 400, "initial.mesh"},
      {"POST", exec, With([](json& j) { j["initial"]["crs"] = "EPSG:4978"; }), 400, "initial.crs"},
      {"POST", exec, With([](json& j) { j["outputs"] = {{"dsm_resolution_m", -1}}; }), 400, "outputs.dsm_resolution_m"},
      {"POST", exec, With([](json& j) { j["initial"]["dsm"] = 1; }), 400, "initial.dsm"},
      {"POST", exec, With([](json& j) { j["initial"]["fill_holes_m"] = -1; }), 400, "initial.fill_holes_m"},
      {"POST", exec, With([](json& j) { j["initial"]["fill_holes_m"] = "far"; }), 400, "initial.fill_holes_m"},
      {"POST", exec, With([](json& j) { j["extra"] = 1; }), 400, "extra"},
      {"POST", exec, With([](json& j) { j["images"][0]["gain"] = 1; }), 400, "images[0].gain"},
      {"POST", exec, With([](json& j) { j["options"] = 3; }), 400, "options"},
      {"POST", exec, With([](json& j) { j["options"]["speed"] = 3; }), 400, "options.speed"},
      {"POST", exec, With([](json& j) { j["options"]["levels"] = "2"; }), 400, "options.levels"},
      {"POST", exec, With([](json& j) { j["options"]["levels"] = 99; }), 400, "levels"},
      {"POST", exec, With([](json& j) { j["options"]["iterations_per_level"] = -1; }), 400, "iterations"},
      {"POST", exec, With([](json& j) { j["options"]["levels"] = 1.5; }), 400, "options.levels"},
      {"POST", exec, With([](json& j) { j["options"]["hit_maps_every"] = 0; }), 400, "hit_maps_every"},
      {"POST", exec, With([](json& j) { j["options"]["hit_maps_every"] = "2"; }), 400, "options.hit_maps_every"},
      {"POST", exec, With([](json& j) { j["outputs"] = {{"crs", 4326}}; }), 400, "outputs.crs"},
      {"POST", exec, With([](json& j) { j["images"][1]["href"] = "nope.tif"; }), 400, "images[1].href"},
      {"POST", exec, With([](json& j) { j["images"][0]["href"] = "../a.tif"; }), 403, "images[0].href"},
      {"POST", exec, With([](json& j) { j["images"][0]["href"] = "sub/../../../etc/passwd"; }), 403, "images[0].href"},
      {"POST", exec, With([](json& j) { j["initial"]["dsm"] = "/etc/passwd"; }), 403, "initial.dsm"},
      {"POST", exec, With([](json& j) { j["initial"]["mesh"] = "/etc"; }), 403, "initial.mesh"},
      {"POST", exec, With([](json& j) { j["images"][1]["href"] = "escape/passwd"; }), 403, "images[1].href"},
      {"POST", exec, With([](json& j) { j["images"][0]["href"] = "/vsicurl/http://example.com/a.tif"; }), 403, "images[0].href"},
      {"POST", exec, With([](json& j) { j["images"][0]["href"] = "/vsis3/bucket/a.tif"; }), 403, "images[0].href"},
      {"POST", exec, With([](json& j) { j["images"][0]["href"] = "sub"; }), 400, "images[0].href"},
      {"POST", exec, With([](json& j) { for (int i = 0; i < 8; ++i) j["images"].push_back({{"href", "a.tif"}}); }), 400, "limit of 8"},
      {"POST", exec, With([](json& j) {  // 500 images: refused before any href is looked up
         for (int i = 2; i < 500; ++i) j["images"].push_back({{"href", "missing_" + std::to_string(i) + ".tif"}});
       }), 400, "images: 500 images exceed this server's limit of 8"},
      {"POST", exec, std::string(2 << 20, ' '), 413, ""},
      {"POST", exec, Job().dump(), 415, "Content-Type", "text/plain"},
      {"POST", "/processes/nope/execution", Job().dump(), 404, "nope"},
      {"POST", exec, json{{"inputs", 5}}.dump(), 400, "job"},
      {"GET", "/processes/nope", "", 404, "nope"},
      {"GET", "/jobs/doesnotexist", "", 404, "doesnotexist"},
      {"DELETE", "/jobs/doesnotexist", "", 404, "doesnotexist"},
      {"GET", "/jobs/doesnotexist/results", "", 404, "doesnotexist"},
      {"GET", "/jobs/doesnotexist/tiles", "", 404, "doesnotexist"},
      {"GET", "/jobs/doesnotexist/tiles/0_0.glb", "", 404, "doesnotexist"},
      {"GET", "/jobs/doesnotexist/events", "", 404, "doesnotexist"},
      {"GET", "/jobs?status=bogus", "", 400, "status"},
      {"GET", "/jobs?limit=abc", "", 400, "limit"},
      {"GET", "/jobs?limit=0", "", 400, "limit"},
      {"GET", "/jobs/" + job_id + "/tiles/9_9.glb", "", 404, "9_9"},
      {"GET", "/jobs/" + job_id + "/results/job.json", "", 404, ""},
      {"GET", "/jobs/" + job_id + "/results/state.json", "", 404, ""},
      {"GET", "/no/such/route", "", 404, ""},
      // Paths from the request line (RELIABILITY.md): encoded traversal out of the viewer's
      // static mount or into the job store, NUL bytes, a job id that is a path.
      {"GET", "/viewer/Cesium/..%2f..%2f..%2f..%2f..%2f..%2fetc%2fpasswd", "", 404, ""},
      {"GET", "/viewer/Cesium/%2e%2e/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd", "", 404, ""},
      {"GET", "/viewer/Cesium/Cesium.js%00.html", "", 400, "NUL byte"},  // was Cesium.js as text/html
      {"GET", "/jobs/..%2f..%2fjobs%2f" + job_id + "/results/job.json", "", 404, ""},
      {"GET", "/jobs/%2e%2e", "", 404, "no job with id '..'"},
      // Invalid UTF-8 in the path: the 404's detail could not be serialised and the error
      // handler's exception terminated the server (fuzz_http); now U+FFFD stands in.
      {"GET", "/jobs/" + job_id + "/tiles/0_0.g%FF%FE%FF.glb", "", 404, "/tiles/0_0.g\xEF\xBF\xBD"},
      {"GET", "/no/%C3%28/route", "", 404, "GET /no/\xEF\xBF\xBD(/route"},
      {"GET", "/jobs/" + job_id + "%00/results/tileset.json", "", 400, "NUL byte"},
      {"DELETE", "/jobs/%2e%2e%2f" + job_id, "", 404, "DELETE /jobs/../" + job_id + ": HTTP 404"},  // no route: the job lives on
  };
  return c;
}

TEST(Malformed, EveryRequestGetsTheRightProblemAndTheServerStaysHealthy) {
  TestServer s("malformed", Stub(1, 1, 10));
  MakeStubJob(s.root);
  std::filesystem::create_directories(s.root + "/sub");
  std::filesystem::create_symlink("/etc", s.root + "/escape");
  s.options.max_body_bytes = 1 << 20;
  s.Start();
  auto c = s.Client();
  const std::string id = Submit(s, Job());
  ASSERT_FALSE(id.empty());
  const auto cases = Cases(id);
  ASSERT_GE(cases.size(), 50u);
  for (const Case& k : cases) {
    httplib::Result r = k.method == "POST"   ? c.Post(k.path.c_str(), k.body, k.content_type.c_str())
                        : k.method == "GET" ? c.Get(k.path.c_str())
                                            : c.Delete(k.path.c_str());
    ASSERT_TRUE(r) << k.method << " " << k.path << ": no response";
    EXPECT_EQ(r->status, k.status) << k.path << " " << k.body.substr(0, 120) << " -> " << r->body;
    if (k.status == 413 && r->body.empty()) continue;  // httplib may close before the body
    EXPECT_EQ(r->get_header_value("Content-Type"), "application/problem+json") << k.path;
    const json p = Json(r);
    EXPECT_EQ(p.value("status", 0), k.status);
    EXPECT_NE(p.value("detail", "").find(k.detail), std::string::npos)
        << k.body.substr(0, 120) << " -> " << p.dump();
  }
  EXPECT_EQ(Json(c.Get("/health"))["status"], "ok");
  EXPECT_EQ(WaitFor(s, id, "successful")["status"], "successful");
  EXPECT_EQ(Json(c.Get("/jobs"))["jobs"].size(), 1u);  // none of the bad requests made a job
}

}  // namespace
}  // namespace satmesh::server::testing
