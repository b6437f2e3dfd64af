#include "core/mesh/mesh_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/common/error.h"
#include "core/mesh/mesh_io_internal.h"

namespace satmesh {
namespace {

std::string Extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

namespace mesh_io_internal {

std::string ReadFileBytes(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    ThrowError(ErrorCode::kNotFound, "mesh file not found: " + path);
  std::ifstream in(path, std::ios::binary);
  SATMESH_CHECK(in.good(), ErrorCode::kIo, "cannot open mesh file " + path);
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  std::string bytes(size_t(std::max<std::streamoff>(size, 0)), '\0');
  in.read(bytes.data(), std::streamsize(bytes.size()));
  SATMESH_CHECK(in.good() || in.eof(), ErrorCode::kIo, "cannot read mesh file " + path);
  return bytes;
}

void WriteFileBytes(const std::string& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) ThrowIoError("cannot create mesh file " + path, errno);
  for (size_t written = 0; written < bytes.size();) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n < 0 ? errno : ENOSPC;  // a 0-byte write: the device took nothing
      ::close(fd);
      ThrowIoError("cannot write mesh file " + path, error);
    }
    written += size_t(n);
  }
  if (::close(fd) != 0) ThrowIoError("cannot write mesh file " + path, errno);
}

void SetTileLocalVertices(const std::string& path, const std::vector<double>& xyz,
                          TriangleMesh* mesh) {
  const size_t n = xyz.size() / 3;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    if (!p.allFinite())
      ThrowError(ErrorCode::kInvalidInput,
                 path + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  mesh->origin = n ? Eigen::Vector3d((0.5 * (lo + hi)).array().round()) : Eigen::Vector3d::Zero();
  mesh->vertices.resize(n);
  for (size_t i = 0; i < n; ++i)
    mesh->vertices[i] = (Eigen::Vector3d(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]) -
                         mesh->origin).cast<float>();
}

void AddPolygon(const std::string& path, const char* kind, size_t number,
                const long long* corners, int count, long long num_vertices, TriangleMesh* mesh) {
  const auto polygon = [&] { return std::string(kind) + " " + std::to_string(number); };
  if (count < 3)
    ThrowError(ErrorCode::kInvalidInput, path + ": " + polygon() + " has " +
                                             std::to_string(count) + " vertices (need >= 3)");
  for (int k = 0; k < count; ++k)
    if (corners[k] < 0 || corners[k] >= num_vertices)
      ThrowError(ErrorCode::kInvalidInput,
                 path + ": " + polygon() + " has vertex index " + std::to_string(corners[k]) +
                     " out of range [0, " + std::to_string(num_vertices) + ")");
  for (int k = 1; k + 1 < count; ++k)
    mesh->faces.emplace_back(int(corners[0]), int(corners[k]), int(corners[k + 1]));
}

}  // namespace mesh_io_internal

std::string MeshWriteOptions::Check() const {
  if (draco_position_bits < 8 || draco_position_bits > 30)
    return "draco_position_bits must be in [8, 30], got " + std::to_string(draco_position_bits);
  if (draco_speed < 0 || draco_speed > 10)
    return "draco_speed must be in [0, 10], got " + std::to_string(draco_speed);
  if (draco_normal_bits < 6 || draco_normal_bits > 16)
    return "draco_normal_bits must be in [6, 16], got " + std::to_string(draco_normal_bits);
  if (draco_scalar_bits < 8 || draco_scalar_bits > 24)
    return "draco_scalar_bits must be in [8, 24], got " + std::to_string(draco_scalar_bits);
  return "";
}

void WriteGlb(const std::string& path, const TriangleMesh& mesh, const std::vector<VertexScalar>& scalars,
              const MeshWriteOptions& options) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument,
                "MeshWriteOptions for " + path + ": " + problem);
  ValidateMesh(mesh, path);
  for (const auto& s : scalars) {
    const bool named = s.name.size() > 1 && s.name[0] == '_' &&
                       s.name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") == std::string::npos;
    SATMESH_CHECK(named, ErrorCode::kInvalidArgument,
                  path + ": vertex scalar name '" + s.name + "' is not of the form _[A-Z0-9_]+");
    SATMESH_CHECK(s.values.size() == mesh.vertices.size(), ErrorCode::kInvalidArgument,
                  path + ": vertex scalar " + s.name + " has " + std::to_string(s.values.size()) +
                      " values for " + std::to_string(mesh.vertices.size()) + " vertices");
    for (size_t i = 0; i < s.values.size(); ++i)
      SATMESH_CHECK(std::isfinite(s.values[i]), ErrorCode::kInvalidArgument,
                    path + ": vertex scalar " + s.name + " is not finite at vertex " + std::to_string(i));
  }
  SATMESH_CHECK(Extension(path) == ".glb", ErrorCode::kInvalidArgument, "WriteGlb: not a .glb path: " + path);
  mesh_io_internal::WriteGlb(path, mesh, scalars, options);
}

void WriteMesh(const std::string& path, const TriangleMesh& mesh, const MeshWriteOptions& options) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument,
                "MeshWriteOptions for " + path + ": " + problem);
  ValidateMesh(mesh, path);
  const std::string ext = Extension(path);
  if (ext == ".ply") return mesh_io_internal::WritePly(path, mesh, options);
  if (ext == ".obj") return mesh_io_internal::WriteObj(path, mesh);
  if (ext == ".drc") return mesh_io_internal::WriteDraco(path, mesh, options);
  if (ext == ".glb") return mesh_io_internal::WriteGlb(path, mesh, {}, options);
  ThrowError(ErrorCode::kInvalidArgument,
             "unknown mesh extension '" + ext + "' (use .ply, .obj, .drc, .glb): " + path);
}

TriangleMesh ReadMesh(const std::string& path) {
  const std::string ext = Extension(path);
  TriangleMesh mesh;
  if (ext == ".ply") mesh = mesh_io_internal::ReadPly(path);
  else if (ext == ".obj") mesh = mesh_io_internal::ReadObj(path);
  else if (ext == ".drc") mesh = mesh_io_internal::ReadDraco(path);
  else if (ext == ".glb") mesh = mesh_io_internal::ReadGlb(path);
  else
    ThrowError(ErrorCode::kInvalidArgument,
               "unknown mesh extension '" + ext + "' (use .ply, .obj, .drc, .glb): " + path);
  ValidateMesh(mesh, path);
  return mesh;
}

}  // namespace satmesh
