// Draco (.drc) and glTF binary with KHR_draco_mesh_compression (.glb), tile-local.
#include <algorithm>
#include <cmath>
#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/core/decoder_buffer.h>
#include <draco/core/encoder_buffer.h>
#include <draco/io/gltf_encoder.h>
#include <draco/mesh/mesh.h>
#include <draco/metadata/geometry_metadata.h>
#include <draco/metadata/metadata_decoder.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/common/error.h"
#include "core/mesh/mesh_io_internal.h"
#include "core/mesh/topology.h"

namespace satmesh::mesh_io_internal {
namespace {

// Indexed draco::Mesh with one float32 position attribute (point i = vertex i).
std::unique_ptr<draco::Mesh> ToDracoMesh(const TriangleMesh& mesh) {
  auto out = std::make_unique<draco::Mesh>();
  out->set_num_points(uint32_t(mesh.vertices.size()));
  draco::GeometryAttribute position;
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32,
                /*normalized=*/false, sizeof(float) * 3, 0);
  const int att_id = out->AddAttribute(position, /*identity_mapping=*/true,
                                       uint32_t(mesh.vertices.size()));
  draco::PointAttribute* att = out->attribute(att_id);
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    att->SetAttributeValue(draco::AttributeValueIndex(uint32_t(i)), mesh.vertices[i].data());
  out->SetNumFaces(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    draco::Mesh::Face face;
    for (int k = 0; k < 3; ++k) face[k] = draco::PointIndex(uint32_t(mesh.faces[f][k]));
    out->SetFace(draco::FaceIndex(uint32_t(f)), face);
  }
  return out;
}

// Adds a float attribute of `components` values per point (point i = vertex i) from
// `values` (num_points x components floats); returns its id.
int AddVertexAttribute(draco::GeometryAttribute::Type type, int components, const float* values,
                       draco::Mesh* mesh) {
  draco::GeometryAttribute attribute;
  attribute.Init(type, nullptr, uint8_t(components), draco::DT_FLOAT32, /*normalized=*/false,
                 int64_t(sizeof(float)) * components, 0);
  const int att_id = mesh->AddAttribute(attribute, /*identity_mapping=*/true, mesh->num_points());
  draco::PointAttribute* att = mesh->attribute(att_id);
  for (uint32_t i = 0; i < mesh->num_points(); ++i)
    att->SetAttributeValue(draco::AttributeValueIndex(i), values + size_t(i) * components);
  return att_id;
}

// Points become vertices (positions as float), faces keep their corner order.
TriangleMesh FromDracoMesh(const std::string& path, const draco::Mesh& in) {
  const draco::PointAttribute* att = in.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  SATMESH_CHECK(att != nullptr && att->num_components() == 3, ErrorCode::kInvalidInput,
                path + ": Draco mesh has no 3-component position attribute");
  // Numbers only: converting a bool attribute reads bytes as bool (undefined behaviour
  // in Draco's ConvertTypedValue; found by fuzz_drc).
  const draco::DataType type = att->data_type();
  SATMESH_CHECK(type >= draco::DT_INT8 && type <= draco::DT_FLOAT64, ErrorCode::kInvalidInput,
                path + ": Draco position attribute has data type " + std::to_string(int(type)) +
                    ", not a number type");
  TriangleMesh mesh;
  mesh.vertices.resize(in.num_points());
  for (uint32_t p = 0; p < in.num_points(); ++p) {
    float xyz[3];
    const bool ok = att->ConvertValue<float, 3>(att->mapped_index(draco::PointIndex(p)), xyz);
    if (!ok || !std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2]))
      ThrowError(ErrorCode::kInvalidInput, path + ": bad Draco position " + std::to_string(p));
    mesh.vertices[p] = Eigen::Vector3f(xyz[0], xyz[1], xyz[2]);
  }
  mesh.faces.resize(in.num_faces());
  for (uint32_t f = 0; f < in.num_faces(); ++f) {
    const draco::Mesh::Face& face = in.face(draco::FaceIndex(f));
    for (int k = 0; k < 3; ++k)
      SATMESH_CHECK(face[k].value() < in.num_points(), ErrorCode::kInvalidInput,
                    path + ": Draco face " + std::to_string(f) + " has vertex " +
                        std::to_string(face[k].value()) + " of " + std::to_string(in.num_points()));
    mesh.faces[f] = Eigen::Vector3i(int(face[0].value()), int(face[1].value()), int(face[2].value()));
  }
  return mesh;
}

std::string BufferBytes(const draco::EncoderBuffer& buffer) {
  return std::string(buffer.data(), buffer.size());
}

// Draco (1.5) sizes its corner table from the face and vertex counts in the stream before
// reading the symbols, so ~30 bytes claiming 2^28 faces allocate gigabytes (found by
// fuzz_drc). Refuse counts the stream cannot encode: edgebreaker needs ~1 bit per face,
// so 1000 faces or vertices per byte is far beyond any real file (our tiles: < 1 per byte).
// Checked for the 2.2 bitstream that our writer and every Draco since 1.0 (2017) emit;
// older bitstreams (fixed-size counts, found by fuzz_drc to allocate gigabytes too) are
// refused. Where the header flags metadata, the counts follow it: Draco's own metadata
// decoder finds where (fuzz_drc found 111 bytes with metadata declaring 3 GB).
void CheckDracoCounts(const std::string& path, const char* data, size_t size) {
  const auto* b = reinterpret_cast<const unsigned char*>(data);
  if (size < 12 || std::string(data, 5) != "DRACO") return;  // Draco names what is wrong
  SATMESH_CHECK(b[5] == 2 && b[6] == 2, ErrorCode::kInvalidInput,
                "Draco data in " + path + ": bitstream version " + std::to_string(b[5]) + "." +
                    std::to_string(b[6]) + " is not supported (2.2, written by Draco >= 1.0)");
  if (b[7] != 1) return;  // a point cloud: no faces
  size_t at = 11;  // after the header
  if ((b[9] | (b[10] << 8)) & 0x8000) {  // metadata precedes the connectivity
    draco::DecoderBuffer buffer;
    buffer.Init(data, size);
    buffer.set_bitstream_version(DRACO_BITSTREAM_VERSION(2, 2));
    draco::GeometryMetadata metadata;
    buffer.StartDecodingFrom(int64_t(at));
    if (!draco::MetadataDecoder().DecodeGeometryMetadata(&buffer, &metadata))
      return;  // Draco names what is wrong
    at = size_t(buffer.decoded_size());
  }
  if (b[8] == 1) ++at;  // edgebreaker: a traversal-type byte first
  // Edgebreaker: vertices, faces, (a byte), symbols, split symbols; sequential: faces, points.
  const bool edgebreaker = b[8] == 1;
  uint64_t counts[4] = {0, 0, 0, 0};
  for (int k = 0; k < (edgebreaker ? 4 : 2); ++k) {
    if (edgebreaker && k == 2) ++at;  // num_attribute_data
    for (int shift = 0; at < size && shift < 35; shift += 7) {
      counts[k] |= uint64_t(b[at] & 0x7f) << shift;
      if (!(b[at++] & 0x80)) break;
    }
  }
  const uint64_t limit = 1000 * uint64_t(size);
  if (*std::max_element(counts, counts + 4) > limit)
    ThrowError(ErrorCode::kInvalidInput,
               "Draco data in " + path + ": stream of " + std::to_string(size) + " bytes declares " +
                   std::to_string(counts[0]) + " and " + std::to_string(counts[1]) +
                   " faces/vertices (or symbols " + std::to_string(counts[2]) + ", " +
                   std::to_string(counts[3]) + "), more than it can encode");
}

TriangleMesh DecodeDracoBytes(const std::string& path, const char* data, size_t size) {
  CheckDracoCounts(path, data, size);
  draco::DecoderBuffer buffer;
  buffer.Init(data, size);
  draco::Decoder decoder;
  auto result = decoder.DecodeMeshFromBuffer(&buffer);
  SATMESH_CHECK(result.ok() && result.value() != nullptr, ErrorCode::kInvalidInput,
                path + ": not a valid Draco mesh: " + result.status().error_msg_string());
  return FromDracoMesh(path, *result.value());
}

uint32_t LoadU32(const std::string& bytes, size_t offset) {
  uint32_t v;
  std::memcpy(&v, bytes.data() + offset, 4);
  return v;  // GLB is little endian, as is every platform we build on
}

// The JSON and BIN chunks of a GLB file (glTF 2.0 binary container).
void SplitGlb(const std::string& path, const std::string& bytes, nlohmann::json* json,
              std::string_view* bin) {
  const auto bad = [&](const std::string& why) {
    ThrowError(ErrorCode::kInvalidInput, path + ": not a valid GLB file: " + why);
  };
  if (bytes.size() < 20 || bytes.compare(0, 4, "glTF") != 0) bad("no glTF magic");
  if (LoadU32(bytes, 4) != 2) bad("version is not 2");
  if (LoadU32(bytes, 8) > bytes.size()) bad("truncated (header length exceeds file size)");
  size_t pos = 12;
  while (pos + 8 <= bytes.size()) {
    const size_t length = LoadU32(bytes, pos), type = LoadU32(bytes, pos + 4);
    if (pos + 8 + length > bytes.size()) bad("truncated chunk");
    const std::string_view chunk(bytes.data() + pos + 8, length);
    if (type == 0x4E4F534Au) *json = nlohmann::json::parse(chunk, nullptr, /*allow_exceptions=*/false);
    if (type == 0x004E4942u) *bin = chunk;
    pos += 8 + length;
  }
  if (json->is_discarded() || !json->is_object()) bad("missing or malformed JSON chunk");
}

}  // namespace

void WriteDraco(const std::string& path, const TriangleMesh& mesh, const MeshWriteOptions& options) {
  const std::unique_ptr<draco::Mesh> dmesh = ToDracoMesh(mesh);
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, options.draco_position_bits);
  encoder.SetSpeedOptions(options.draco_speed, options.draco_speed);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(*dmesh, &buffer);
  SATMESH_CHECK(status.ok(), ErrorCode::kIo,
                "Draco encoding failed for " + path + ": " + status.error_msg_string());
  WriteFileBytes(path, BufferBytes(buffer));
}

TriangleMesh ReadDraco(const std::string& path) {
  const std::string bytes = ReadFileBytes(path);
  return DecodeDracoBytes(path, bytes.data(), bytes.size());
}

void WriteGlb(const std::string& path, const TriangleMesh& mesh, const std::vector<VertexScalar>& scalars,
              const MeshWriteOptions& options) {
  const std::unique_ptr<draco::Mesh> dmesh = ToDracoMesh(mesh);
  // Area-weighted unit normals; glTF requires unit length, so a vertex on no face (or
  // only degenerate ones) gets +z.
  std::vector<Eigen::Vector3f> normals = VertexNormals(mesh);
  for (auto& n : normals)
    if (n.squaredNorm() < 0.5f) n = Eigen::Vector3f::UnitZ();
  AddVertexAttribute(draco::GeometryAttribute::NORMAL, 3, reinterpret_cast<const float*>(normals.data()), dmesh.get());
  for (const auto& s : scalars) {
    const int att_id = AddVertexAttribute(draco::GeometryAttribute::GENERIC, 1, s.values.data(), dmesh.get());
    // The glTF attribute name travels as the attribute's metadata (draco::GltfEncoder).
    auto metadata = std::make_unique<draco::AttributeMetadata>();
    metadata->AddEntryString(draco::GltfEncoder::kDracoMetadataGltfAttributeName, s.name);
    dmesh->AddAttributeMetadata(att_id, std::move(metadata));
  }
  draco::DracoCompressionOptions compression;
  compression.quantization_position.SetQuantizationBits(options.draco_position_bits);
  compression.quantization_bits_normal = options.draco_normal_bits;
  compression.quantization_bits_generic = options.draco_scalar_bits;
  compression.compression_level = 10 - options.draco_speed;  // speed 0 = most compression
  dmesh->SetCompressionEnabled(true);
  dmesh->SetCompressionOptions(compression);
  draco::GltfEncoder encoder;
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeToBuffer(*dmesh, &buffer);
  SATMESH_CHECK(status.ok(), ErrorCode::kIo,
                "glTF encoding failed for " + path + ": " + status.error_msg_string());
  WriteFileBytes(path, BufferBytes(buffer));
}

// Reads every Draco-compressed primitive of every mesh (node transforms are not applied:
// our .glb tiles carry tile-local positions) and concatenates them.
TriangleMesh ReadGlb(const std::string& path) {
  const std::string bytes = ReadFileBytes(path);
  nlohmann::json json;
  std::string_view bin;
  SplitGlb(path, bytes, &json, &bin);
  TriangleMesh mesh;
  try {
    for (const auto& gltf_mesh : json.value("meshes", nlohmann::json::array())) {
      for (const auto& primitive : gltf_mesh.at("primitives")) {
        if (primitive.value("mode", 4) != 4)
          ThrowError(ErrorCode::kInvalidInput, path + ": only triangle primitives are supported");
        const auto ext = primitive.value("extensions", nlohmann::json::object());
        if (!ext.contains("KHR_draco_mesh_compression"))
          ThrowError(ErrorCode::kInvalidInput,
                     path + ": primitive without KHR_draco_mesh_compression is not supported");
        const auto& view = json.at("bufferViews").at(
            ext["KHR_draco_mesh_compression"].at("bufferView").get<size_t>());
        const size_t offset = view.value("byteOffset", size_t(0));
        const size_t length = view.at("byteLength").get<size_t>();
        if (offset + length > bin.size())
          ThrowError(ErrorCode::kInvalidInput, path + ": Draco buffer view exceeds the BIN chunk");
        const TriangleMesh part = DecodeDracoBytes(path, bin.data() + offset, length);
        const int base = int(mesh.vertices.size());
        mesh.vertices.insert(mesh.vertices.end(), part.vertices.begin(), part.vertices.end());
        for (const auto& f : part.faces) mesh.faces.push_back(f + Eigen::Vector3i::Constant(base));
      }
    }
  } catch (const nlohmann::json::exception& e) {
    ThrowError(ErrorCode::kInvalidInput, path + ": malformed glTF JSON: " + e.what());
  }
  return mesh;
}

}  // namespace satmesh::mesh_io_internal
