// libFuzzer target: one mesh reader (PLY, OBJ, Draco or glb: SATMESH_FUZZ_EXT picks the
// extension, so ReadMesh's dispatch is part of what runs). A file either reads into a
// valid mesh (finite vertices, indices in range) or throws Error{kInvalidInput}
// naming the file; anything else (crash, other exception, invalid mesh) is a finding.
#include <cmath>

#include "core/common/error.h"
#include "core/mesh/mesh_io.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace satmesh;
  static const std::string path = fuzz::ScratchFile(SATMESH_FUZZ_EXT);
  fuzz::WriteBytes(path, data, size);
  TriangleMesh mesh;
  try {
    mesh = ReadMesh(path);
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kInvalidInput) fuzz::Fail(std::string("error code ") + ErrorCodeName(e.code()) + ": " + e.what());
    if (std::string(e.what()).find(path) == std::string::npos) fuzz::Fail(std::string("message without the file: ") + e.what());
    return 0;
  }
  for (const auto& v : mesh.vertices)
    if (!v.allFinite()) fuzz::Fail("a non-finite vertex was returned");
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k)
      if (f[k] < 0 || size_t(f[k]) >= mesh.vertices.size()) fuzz::Fail("a face index out of range was returned");
  return 0;
}
