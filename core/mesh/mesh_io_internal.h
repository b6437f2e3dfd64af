#pragma once
// Per-format readers/writers behind mesh_io.h (private to the mesh module).
#include <string>
#include <vector>

#include "core/mesh/mesh_io.h"

namespace satmesh::mesh_io_internal {

void WritePly(const std::string& path, const TriangleMesh& mesh, const MeshWriteOptions& options);
TriangleMesh ReadPly(const std::string& path);
void WriteObj(const std::string& path, const TriangleMesh& mesh);
TriangleMesh ReadObj(const std::string& path);
void WriteDraco(const std::string& path, const TriangleMesh& mesh, const MeshWriteOptions& options);
TriangleMesh ReadDraco(const std::string& path);
void WriteGlb(const std::string& path, const TriangleMesh& mesh, const std::vector<VertexScalar>& scalars,
              const MeshWriteOptions& options);
TriangleMesh ReadGlb(const std::string& path);

// Whole file as bytes; throws kNotFound / kIo naming the file.
std::string ReadFileBytes(const std::string& path);
// Writes bytes to a file; throws kIo naming the file.
void WriteFileBytes(const std::string& path, const std::string& bytes);

// Absolute double positions -> origin (bounding-box centre rounded to metres) + float
// tile-local vertices. Throws kInvalidInput naming `path` and the first non-finite vertex.
void SetTileLocalVertices(const std::string& path, const std::vector<double>& xyz,
                          TriangleMesh* mesh);
// Appends triangles of polygon `corners` (fan around corners[0]) after checking each
// index in [0, num_vertices). Errors name the polygon as "<kind> <number>".
void AddPolygon(const std::string& path, const char* kind, size_t number,
                const long long* corners, int count, long long num_vertices, TriangleMesh* mesh);

}  // namespace satmesh::mesh_io_internal
