// Jobs from a mesh through the real server over loopback: the scene's truth mesh
// submitted, polled to success and compared with the in-process (CLI) run; the result
// chained into a second job; bad meshes refused with a 400 naming the problem.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/dsm/dsm.h"
#include "core/mesh/mesh_io.h"
#include "core/synth/scene_writer.h"
#include "tests/tiny_scene.h"
#include "core/tiling/job.h"
#include "proto/job_spec_json.h"
#include "server/api_documents.h"
#include "server/real_executor.h"
#include "tests/server/test_server.h"

namespace satmesh::server::testing {
namespace {

using nlohmann::json;

json WaitForEnd(httplib::Client& c, const std::string& id) {
  json info;
  for (int i = 0; i < 3000; ++i) {  // <= 300 s
    info = Json(c.Get(("/jobs/" + id).c_str()));
    if (info["status"] != "accepted" && info["status"] != "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return info;
}

TEST(MeshJobOverHttp, EqualsTheCliRunChainsAndRefusesBadMeshes) {
  const std::string dir = TempDir("mesh_e2e");
  const std::string scene = dir + "/scene";
  const synth::SynthOptions o = satmesh::testing::TinySceneOptions();
  synth::GenerateScene(scene, o);
  const Dsm initial = ReadDsm(scene + "/initial/dsm.tif");
  const double x0 = initial.geo_transform[0], y1 = initial.geo_transform[3];
  const double x1 = x0 + initial.width * initial.geo_transform[1];
  const double y0 = y1 + initial.height * initial.geo_transform[5];
  json job = ReadJsonFile(scene + "/job.json");
  job["initial"] = {{"mesh", "truth/mesh.ply"}};
  job["aoi"] = {{"bbox", {x0, y0, x1, y1}}};
  job["tiling"] = {{"size_m", 18}, {"overlap_m", 3}};
  job["options"]["levels"] = 1;
  job["options"]["iterations_per_level"] = 3;
  const TriangleMesh truth = ReadMesh(scene + "/truth/mesh.ply");

  RealExecutor executor;
  ServerOptions options;
  options.port = 0;
  options.data_dir = dir + "/data";
  std::filesystem::create_directories(options.data_dir);
  options.inputs.data_roots = {scene, options.data_dir};  // results may be chained
  options.inputs.max_mesh_faces = truth.num_faces();
  options.scheduler.workers = 2;
  ApiServer server(options, &executor);
  httplib::Client c("127.0.0.1", server.Start());
  c.set_read_timeout(30, 0);
  auto r = c.Post("/processes/refine-mesh/execution", job.dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const std::string id = Json(r)["jobID"];
  const json info = WaitForEnd(c, id);
  ASSERT_EQ(info["status"], "successful") << info.dump();
  const json served = Json(c.Get(("/jobs/" + id + "/results").c_str()))["metrics"]["value"];

  // The CLI's path: the same job in-process.
  const JobOutputs local = RunJob(proto::JobSpecFromJson(job, scene), dir + "/local");
  const json expected = proto::JobMetricsToJson(local);
  ASSERT_EQ(served["tiles"].size(), 4u);
  ASSERT_EQ(served["tiles"].size(), expected["tiles"].size());
  for (size_t t = 0; t < expected["tiles"].size(); ++t) {
    EXPECT_EQ(served["tiles"][t]["name"], expected["tiles"][t]["name"]);
    EXPECT_EQ(served["tiles"][t]["faces"], expected["tiles"][t]["faces"]);
    EXPECT_NEAR(served["tiles"][t]["levels"].back()["mean_zncc_end"].get<double>(),
                expected["tiles"][t]["levels"].back()["mean_zncc_end"].get<double>(), 1e-4);
  }
  EXPECT_EQ(served["totals"]["faces"], expected["totals"]["faces"]);

  // Chaining: the first job's result directory as the next job's initial mesh.
  json chained = job;
  chained["initial"] = {{"mesh", options.data_dir + "/jobs/" + id}};  // the store's layout
  r = c.Post("/processes/refine-mesh/execution", chained.dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const json chained_info = WaitForEnd(c, Json(r)["jobID"]);
  EXPECT_EQ(chained_info["status"], "successful") << chained_info.dump();

  // Bad meshes: 400, naming the problem.
  std::ofstream(scene + "/nan.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                                       "property double y\nproperty double z\nelement face 1\n"
                                       "property list uchar int vertex_indices\nend_header\n"
                                       "0 0 0\nnan 1 0\n1 0 0\n3 0 1 2\n";
  std::ofstream(scene + "/garbage.ply") << "not a mesh\n";
  TriangleMesh bigger = truth;
  bigger.faces.push_back(bigger.faces.front());
  WriteMesh(scene + "/bigger.ply", bigger);
  const std::vector<std::pair<json, std::string>> bad = {
      {{{"mesh", "garbage.ply"}}, "garbage.ply': cannot be read"},
      {{{"mesh", "nan.ply"}, {"crs", "EPSG:32617"}}, "non-finite"},
      {{{"mesh", "missing.ply"}}, "initial.mesh: 'missing.ply' does not exist"},
      {{{"mesh", "bigger.ply"}}, "faces, more than the limit of " + std::to_string(truth.num_faces())},
      {{{"mesh", "truth/mesh.ply"}, {"crs", "EPSG:32618"}}, "outside the images' footprint"},
  };
  for (const auto& [initial_json, message] : bad) {
    json b = job;
    b["initial"] = initial_json;
    auto refused = c.Post("/processes/refine-mesh/execution", b.dump(), "application/json");
    EXPECT_EQ(refused->status, 400) << refused->body;
    EXPECT_NE(Json(refused)["detail"].get<std::string>().find(message), std::string::npos)
        << refused->body << "\nexpected: " << message;
  }
  json outside = job;
  outside["aoi"] = {{"bbox", {x0 + 5000, y0, x1 + 5000, y1}}};
  auto refused = c.Post("/processes/refine-mesh/execution", outside.dump(), "application/json");
  EXPECT_EQ(refused->status, 400) << refused->body;
  EXPECT_NE(refused->body.find("outside the aoi"), std::string::npos) << refused->body;
  server.Stop();
}

}  // namespace
}  // namespace satmesh::server::testing
