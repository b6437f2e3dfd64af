#include "core/mesh/mesh.h"

#include <cmath>

#include "core/common/error.h"

namespace satmesh {

void ValidateMesh(const TriangleMesh& mesh, const std::string& what) {
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3f& v = mesh.vertices[i];
    if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z()))
      ThrowError(ErrorCode::kInvalidInput,
                 what + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
  }
  if (!mesh.origin.allFinite()) ThrowError(ErrorCode::kInvalidInput, what + ": non-finite origin");
  const long long n = (long long)mesh.vertices.size();
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int index = mesh.faces[f][k];
      if (index < 0 || index >= n)
        ThrowError(ErrorCode::kInvalidInput,
                   what + ": face " + std::to_string(f) + " has vertex index " +
                       std::to_string(index) + " out of range [0, " + std::to_string(n) + ")");
    }
  }
}

}  // namespace satmesh
