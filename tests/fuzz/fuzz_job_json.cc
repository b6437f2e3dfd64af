// libFuzzer target: a job submission body through the steps the server's POST
// /processes/refine-mesh/execution takes (server/api.cc, Execute): JSON parse, the
// OGC "inputs"/"inputs.job" unwrapping, href resolution under a data root (ResolveHrefs),
// the job parser (proto::JobSpecFromJson), the spec's Check and the server's limits.
// Allowed outcomes: success, or an exception the server maps to a 4xx (HttpError,
// satmesh::Error other than kIo/kInternal, nlohmann::json::exception); anything else
// would be a 500 or a crash.
#include <filesystem>
#include <fstream>

#include "core/common/error.h"
#include "proto/job_spec_json.h"
#include "server/inputs.h"
#include "server/problem.h"
#include "tests/fuzz/fuzz_util.h"

namespace {
satmesh::server::InputPolicy policy;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / ("satmesh_fuzz_root_" + std::to_string(::getpid()));
  fs::create_directories(root / "sub");
  for (const char* name : {"a.tif", "b.tif", "dsm.tif", "sub/c.tif"}) std::ofstream(root / name) << "x";
  policy.data_roots = {root.string()};
  policy.allowed_vsi = {"/vsicurl/https://data.example.com/"};
  policy.max_images = 16;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace satmesh;
  using nlohmann::json;
  try {
    const json body = json::parse(data, data + size);
    json job = body.is_object() && body.contains("inputs") ? body["inputs"] : body;
    if (job.is_object() && job.size() == 1 && job.contains("job")) {
      job = json(job["job"]);
      if (!job.is_object()) return 0;
    }
    server::ResolveHrefs(&job, policy);
    const JobSpec spec = proto::JobSpecFromJson(job, "/");
    if (!spec.Check().empty()) return 0;
    server::CheckLimits(spec, {}, policy);
  } catch (const server::HttpError& e) {
    if (e.status() >= 500) fuzz::Fail(std::string("HTTP ") + std::to_string(e.status()) + ": " + e.what());
  } catch (const Error& e) {
    if (e.code() == ErrorCode::kIo || e.code() == ErrorCode::kInternal)
      fuzz::Fail(std::string("error code ") + ErrorCodeName(e.code()) + ": " + e.what());
  } catch (const nlohmann::json::exception&) {
  } catch (const std::exception& e) {
    fuzz::Fail(std::string("exception the server answers with 500: ") + e.what());
  }
  return 0;
}
