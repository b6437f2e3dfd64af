// PLY reader and writer (ascii, binary little/big endian).
#include <cerrno>
#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/common/error.h"
#include "core/mesh/mesh_io_internal.h"

namespace satmesh::mesh_io_internal {
namespace {

enum class PlyType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // item type for lists
  bool is_list = false;
  PlyType count_type = PlyType::kUInt8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::string crs;
  size_t data_offset = 0;
};

[[noreturn]] void Fail(const std::string& path, const std::string& problem) {
  ThrowError(ErrorCode::kInvalidInput, path + ": " + problem);
}

bool ParseType(const std::string& name, PlyType* type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},     {"int8", PlyType::kInt8},       {"uchar", PlyType::kUInt8},
      {"uint8", PlyType::kUInt8},   {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUInt16}, {"uint16", PlyType::kUInt16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},   {"uint", PlyType::kUInt32},     {"uint32", PlyType::kUInt32},
      {"float", PlyType::kFloat32}, {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [n, t] : kNames)
    if (name == n) return *type = t, true;
  return false;
}

size_t TypeSize(PlyType t) {
  static const size_t kSizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return kSizes[int(t)];
}

PlyHeader ParseHeader(const std::string& path, const std::string& bytes) {
  if (bytes.compare(0, 3, "ply") != 0) Fail(path, "not a PLY file (no 'ply' magic)");
  PlyHeader header;
  size_t pos = 0;
  bool have_format = false;
  while (true) {
    const size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) Fail(path, "PLY header has no 'end_header' line");
    std::string line = bytes.substr(pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = eol + 1;
    std::istringstream in(line);
    std::string keyword;
    in >> keyword;
    if (keyword == "end_header") break;
    if (keyword == "format") {
      std::string format;
      in >> format;
      if (format == "ascii") header.format = PlyFormat::kAscii;
      else if (format == "binary_little_endian") header.format = PlyFormat::kBinaryLittle;
      else if (format == "binary_big_endian") header.format = PlyFormat::kBinaryBig;
      else Fail(path, "unknown PLY format '" + format + "'");
      have_format = true;
    } else if (keyword == "comment") {
      if (line.rfind("comment crs ", 0) == 0) header.crs = line.substr(12);
    } else if (keyword == "element") {
      PlyElement element;
      long long count = -1;
      in >> element.name >> count;
      if (in.fail() || count < 0) Fail(path, "bad PLY element line '" + line + "'");
      element.count = size_t(count);
      header.elements.push_back(element);
    } else if (keyword == "property") {
      if (header.elements.empty()) Fail(path, "PLY property before any element: '" + line + "'");
      PlyProperty property;
      std::string type;
      in >> type;
      if (type == "list") {
        std::string count_type, item_type;
        in >> count_type >> item_type >> property.name;
        property.is_list = true;
        if (!ParseType(count_type, &property.count_type) || !ParseType(item_type, &property.type))
          Fail(path, "unknown PLY list types in '" + line + "'");
      } else {
        in >> property.name;
        if (!ParseType(type, &property.type)) Fail(path, "unknown PLY type in '" + line + "'");
      }
      if (property.name.empty()) Fail(path, "PLY property without a name: '" + line + "'");
      header.elements.back().properties.push_back(property);
    } else if (keyword != "ply" && keyword != "obj_info" && !keyword.empty()) {
      Fail(path, "unknown PLY header line '" + line + "'");
    }
  }
  if (!have_format) Fail(path, "PLY header has no format line");
  header.data_offset = pos;
  return header;
}

// Reads values of the PLY body one at a time, ascii or binary.
class PlyBody {
 public:
  PlyBody(const std::string& bytes, size_t offset, PlyFormat format)
      : data_(bytes.data()), pos_(offset), size_(bytes.size()), format_(format) {}

  // False at the end of the data.
  bool Read(PlyType type, double* value) {
    return format_ == PlyFormat::kAscii ? ReadAscii(value) : ReadBinary(type, value);
  }
  // Bytes (binary) or tokens (ascii) left after the last element.
  bool HasTrailingData() {
    if (format_ != PlyFormat::kAscii) return pos_ < size_;
    SkipSpace();
    return pos_ < size_;
  }

 private:
  void SkipSpace() {
    while (pos_ < size_ && std::isspace((unsigned char)data_[pos_])) ++pos_;
  }
  bool ReadAscii(double* value) {
    SkipSpace();
    if (pos_ >= size_) return false;
    size_t end = pos_;
    while (end < size_ && !std::isspace((unsigned char)data_[end])) ++end;
    const char* first = data_ + pos_;
    if (*first == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, data_ + end, *value);
    if (ec != std::errc() || ptr != data_ + end) *value = NAN;  // reported by the caller
    pos_ = end;
    return true;
  }
  template <typename T>
  T Load() {
    T v;
    std::memcpy(&v, data_ + pos_, sizeof(T));
    const bool swap = (format_ == PlyFormat::kBinaryBig) == (std::endian::native == std::endian::little);
    if (swap && sizeof(T) > 1) {
      unsigned char b[sizeof(T)];
      std::memcpy(b, &v, sizeof(T));
      for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
      std::memcpy(&v, b, sizeof(T));
    }
    return v;
  }
  bool ReadBinary(PlyType type, double* value) {
    if (pos_ + TypeSize(type) > size_) return false;
    switch (type) {
      case PlyType::kInt8: *value = Load<int8_t>(); break;
      case PlyType::kUInt8: *value = Load<uint8_t>(); break;
      case PlyType::kInt16: *value = Load<int16_t>(); break;
      case PlyType::kUInt16: *value = Load<uint16_t>(); break;
      case PlyType::kInt32: *value = Load<int32_t>(); break;
      case PlyType::kUInt32: *value = Load<uint32_t>(); break;
      case PlyType::kFloat32: *value = Load<float>(); break;
      case PlyType::kFloat64: *value = Load<double>(); break;
    }
    pos_ += TypeSize(type);
    return true;
  }

  const char* data_;
  size_t pos_, size_;
  PlyFormat format_;
};

bool IsFaceList(const std::string& element, const PlyProperty& p) {
  return element == "face" && p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index");
}

// Appends ASCII text of a number (shortest round-trip form).
template <typename T>
void AppendNumber(std::string* out, T value) {
  char buf[40];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  out->append(buf, ptr);
}

template <typename T>
void AppendBinary(std::string* out, T value) {
  static_assert(std::endian::native == std::endian::little, "binary PLY writer assumes little endian");
  out->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

}  // namespace

TriangleMesh ReadPly(const std::string& path) {
  const std::string bytes = ReadFileBytes(path);
  const PlyHeader header = ParseHeader(path, bytes);
  PlyBody body(bytes, header.data_offset, header.format);
  TriangleMesh mesh;
  mesh.crs = header.crs;
  std::vector<double> xyz;
  std::vector<long long> corners;
  long long num_vertices = -1;
  for (const PlyElement& element : header.elements) {
    const bool is_vertex = element.name == "vertex";
    // Every row of an element with properties takes at least a byte; one without has no
    // data to read (3.3e9 empty rows of an unknown element spun for minutes: fuzz_ply).
    if (element.count > bytes.size())
      Fail(path, "PLY header declares " + std::to_string(element.count) + " rows of an element '" +
                     element.name + "', more than the file can hold (truncated?)");
    if (element.properties.empty()) continue;
    // 0/1/2 for x/y/z, 3 for height_sigma, else -1
    std::vector<int> axis(element.properties.size());
    int found = 0;
    for (size_t p = 0; p < element.properties.size(); ++p) {
      const std::string& n = element.properties[p].name;
      axis[p] = !is_vertex || element.properties[p].is_list ? -1
                : n == "x" ? 0 : n == "y" ? 1 : n == "z" ? 2 : n == "height_sigma" ? 3 : -1;
      if (axis[p] >= 0 && axis[p] < 3) ++found;
      if (axis[p] == 3) mesh.height_sigma.assign(element.count, NAN);
    }
    if (is_vertex) {
      if (found != 3) Fail(path, "PLY vertex element lacks scalar x, y, z properties");
      if (element.count > bytes.size() / 3)  // every row takes at least 3 bytes
        Fail(path, "PLY header declares " + std::to_string(element.count) +
                       " vertices, more than the file can hold (truncated?)");
      num_vertices = (long long)element.count;
      xyz.assign(3 * element.count, 0.0);
    }
    if (element.name == "face") {
      if (num_vertices < 0) Fail(path, "PLY face element before the vertex element");
      if (std::none_of(element.properties.begin(), element.properties.end(),
                       [&](const PlyProperty& p) { return IsFaceList(element.name, p); }))
        Fail(path, "PLY face element has no 'vertex_indices' or 'vertex_index' list");
      mesh.faces.reserve(std::min(element.count, bytes.size() / 8));  // bound by file size
    }
    for (size_t row = 0; row < element.count; ++row) {
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        double value = 0;
        const auto where = [&] {
          return "element '" + element.name + "' row " + std::to_string(row) + " of " +
                 std::to_string(element.count) + ", property '" + property.name + "'";
        };
        if (!body.Read(property.is_list ? property.count_type : property.type, &value))
          Fail(path, "PLY file is truncated: data ends in " + where());
        if (!property.is_list) {
          if (axis[p] == 3) mesh.height_sigma[row] = float(value);
          else if (axis[p] >= 0) xyz[3 * row + axis[p]] = value;
          continue;
        }
        if (!(value >= 0 && value <= 1e6) || value != std::floor(value))
          Fail(path, "bad PLY list count " + std::to_string(value) + " in " + where());
        const int count = int(value);
        const bool keep = IsFaceList(element.name, property);
        corners.resize(count);
        for (int k = 0; k < count; ++k) {
          if (!body.Read(property.type, &value))
            Fail(path, "PLY file is truncated: data ends in " + where());
          if (keep && (!std::isfinite(value) || value != std::floor(value)))
            Fail(path, "non-integer vertex index in " + where());
          if (keep && std::abs(value) > 1e15)  // beyond long long's range: UB to convert
            Fail(path, "vertex index " + std::to_string(value) + " out of range in " + where());
          corners[k] = keep ? (long long)value : 0;
        }
        if (keep)
          AddPolygon(path, "face", row, corners.data(), count, num_vertices, &mesh);
      }
    }
  }
  if (num_vertices < 0) Fail(path, "PLY file has no vertex element");
  if (body.HasTrailingData())
    Fail(path, "PLY file has data after the last element: the element counts in the header "
               "do not match the data (header/face count mismatch?)");
  SetTileLocalVertices(path, xyz, &mesh);
  return mesh;
}

void WritePly(const std::string& path, const TriangleMesh& mesh, const MeshWriteOptions& options) {
  const char* type = options.ply_double ? "double" : "float";
  std::string header = "ply\nformat ";
  header += options.ply_binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  header += "comment written by satmesh\n";
  if (!mesh.crs.empty() && mesh.crs.find_first_of("\r\n") == std::string::npos)
    header += "comment crs " + mesh.crs + "\n";
  header += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
  for (const char* axis : {"x", "y", "z"}) header += std::string("property ") + type + " " + axis + "\n";
  const bool with_sigma = mesh.height_sigma.size() == mesh.vertices.size() && !mesh.vertices.empty();
  if (with_sigma) header += "property float height_sigma\n";
  header += "element face " + std::to_string(mesh.faces.size()) + "\n";
  header += "property list uchar int vertex_indices\nend_header\n";

  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  SATMESH_CHECK(out.good(), ErrorCode::kIo, "cannot create PLY file " + path);
  std::string buffer = std::move(header);
  constexpr size_t kFlushBytes = size_t(1) << 22;
  buffer.reserve(kFlushBytes + 256);
  const auto flush = [&](bool force) {
    if (!force && buffer.size() < kFlushBytes) return;
    out.write(buffer.data(), std::streamsize(buffer.size()));
    buffer.clear();
  };
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3d p = mesh.AbsoluteVertex(i);
    for (int k = 0; k < 3; ++k) {
      if (options.ply_binary) {
        options.ply_double ? AppendBinary(&buffer, p[k]) : AppendBinary(&buffer, float(p[k]));
      } else {
        options.ply_double ? AppendNumber(&buffer, p[k]) : AppendNumber(&buffer, float(p[k]));
        buffer += k < 2 || with_sigma ? ' ' : '\n';
      }
    }
    if (with_sigma) {
      const float sigma = mesh.height_sigma[i];
      if (options.ply_binary) AppendBinary(&buffer, sigma);
      else if (std::isfinite(sigma)) AppendNumber(&buffer, sigma), buffer += '\n';
      else buffer += std::isnan(sigma) ? "nan\n" : "inf\n";
    }
    flush(false);
  }
  for (const Eigen::Vector3i& f : mesh.faces) {
    if (options.ply_binary) {
      AppendBinary(&buffer, uint8_t(3));
      for (int k = 0; k < 3; ++k) AppendBinary(&buffer, int32_t(f[k]));
    } else {
      buffer += '3';
      for (int k = 0; k < 3; ++k) buffer += ' ', AppendNumber(&buffer, f[k]);
      buffer += '\n';
    }
    flush(false);
  }
  flush(true);
  out.close();
  if (out.fail()) ThrowIoError("cannot write PLY file " + path, errno);
}

}  // namespace satmesh::mesh_io_internal
