// Wavefront OBJ: v and f lines only (no materials, texture coordinates or normals).
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string_view>

#include "core/common/error.h"
#include "core/mesh/mesh_io_internal.h"

namespace satmesh::mesh_io_internal {
namespace {

std::string_view NextToken(std::string_view* line) {
  size_t b = 0;
  while (b < line->size() && ((*line)[b] == ' ' || (*line)[b] == '\t')) ++b;
  size_t e = b;
  while (e < line->size() && (*line)[e] != ' ' && (*line)[e] != '\t') ++e;
  const std::string_view token = line->substr(b, e - b);
  line->remove_prefix(e);
  return token;
}

template <typename T>
bool ParseNumber(std::string_view token, T* value) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), *value);
  return ec == std::errc() && ptr == token.data() + token.size();
}

template <typename T>
void AppendNumber(std::string* out, T value) {
  char buf[40];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  out->append(buf, ptr);
}

}  // namespace

TriangleMesh ReadObj(const std::string& path) {
  const std::string bytes = ReadFileBytes(path);
  TriangleMesh mesh;
  std::vector<double> xyz;
  // Faces are checked once all vertices are known.
  struct Polygon {
    size_t line, first, count;
  };
  std::vector<Polygon> polygons;
  std::vector<long long> all_corners;
  size_t pos = 0, line_number = 0;
  while (pos < bytes.size()) {
    size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) eol = bytes.size();
    std::string_view line(bytes.data() + pos, eol - pos);
    pos = eol + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const auto where = [&] { return "line " + std::to_string(line_number); };
    const std::string_view keyword = NextToken(&line);
    if (keyword == "#" && line.substr(0, 5) == " crs ") {
      mesh.crs = std::string(line.substr(5));
    } else if (keyword == "v") {
      for (int k = 0; k < 3; ++k) {
        double value;
        if (!ParseNumber(NextToken(&line), &value))
          ThrowError(ErrorCode::kInvalidInput, path + ": bad vertex coordinate on " + where());
        xyz.push_back(value);
      }
    } else if (keyword == "f") {
      const long long num_vertices = (long long)(xyz.size() / 3);
      const size_t first = all_corners.size();
      for (std::string_view token = NextToken(&line); !token.empty(); token = NextToken(&line)) {
        long long index = 0;
        if (!ParseNumber(token.substr(0, token.find('/')), &index) || index == 0)
          ThrowError(ErrorCode::kInvalidInput,
                     path + ": bad face index '" + std::string(token) + "' on " + where());
        all_corners.push_back(index > 0 ? index - 1 : num_vertices + index);  // 0-based
      }
      polygons.push_back({line_number, first, all_corners.size() - first});
    }
  }
  SetTileLocalVertices(path, xyz, &mesh);
  const long long num_vertices = (long long)mesh.vertices.size();
  mesh.faces.reserve(polygons.size());
  for (const Polygon& p : polygons)
    AddPolygon(path, "face on line", p.line, all_corners.data() + p.first, int(p.count),
               num_vertices, &mesh);
  return mesh;
}

void WriteObj(const std::string& path, const TriangleMesh& mesh) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  SATMESH_CHECK(out.good(), ErrorCode::kIo, "cannot create OBJ file " + path);
  std::string buffer = "# written by satmesh\n";
  if (!mesh.crs.empty() && mesh.crs.find_first_of("\r\n") == std::string::npos)
    buffer += "# crs " + mesh.crs + "\n";
  constexpr size_t kFlushBytes = size_t(1) << 22;
  const auto flush = [&](bool force) {
    if (!force && buffer.size() < kFlushBytes) return;
    out.write(buffer.data(), std::streamsize(buffer.size()));
    buffer.clear();
  };
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3d p = mesh.AbsoluteVertex(i);
    buffer += 'v';
    for (int k = 0; k < 3; ++k) buffer += ' ', AppendNumber(&buffer, p[k]);
    buffer += '\n';
    flush(false);
  }
  for (const Eigen::Vector3i& f : mesh.faces) {
    buffer += 'f';
    for (int k = 0; k < 3; ++k) buffer += ' ', AppendNumber(&buffer, f[k] + 1);
    buffer += '\n';
    flush(false);
  }
  flush(true);
  out.close();
  if (out.fail()) ThrowIoError("cannot write OBJ file " + path, errno);
}

}  // namespace satmesh::mesh_io_internal
