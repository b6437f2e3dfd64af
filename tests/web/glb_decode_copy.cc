// A decoded copy of a Draco-compressed .glb: its Draco buffer decoded by Draco's decoder
// and written uncompressed by Draco's glTF encoder (not by satmesh's mesh I/O), so that
// glTF-Validator can check the decoded accessors (normal lengths, bounds, counts) that it
// cannot see inside Draco. Application-specific attributes (_HEIGHT, ...) keep their names.
// (Debian's libdraco-dev lacks tiny_gltf.h, so draco::GltfDecoder cannot be used.)
//   glb_decode_copy IN.glb OUT.glb
#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>
#include <draco/io/gltf_encoder.h>
#include <draco/mesh/mesh.h>
#include <draco/metadata/geometry_metadata.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

namespace {

uint32_t U32(const std::string& b, size_t at) {
  uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

int Fail(const std::string& why) {
  std::fprintf(stderr, "glb_decode_copy: %s\n", why.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: glb_decode_copy IN.glb OUT.glb\n");
    return 2;
  }
  std::ifstream in(argv[1], std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < 28 || bytes.compare(0, 4, "glTF") != 0)
    return Fail(std::string(argv[1]) + ": not a GLB");
  const uint32_t json_length = U32(bytes, 12);
  const auto gltf = nlohmann::json::parse(bytes.substr(20, json_length));
  const size_t bin_at = 20 + json_length + 8;  // the BIN chunk follows the JSON chunk
  const auto& primitives = gltf.at("meshes").at(0).at("primitives");
  if (gltf.at("meshes").size() != 1 || primitives.size() != 1)
    return Fail("expected one mesh, one primitive");
  const auto& draco_ext = primitives[0].at("extensions").at("KHR_draco_mesh_compression");
  const auto& view = gltf.at("bufferViews").at(draco_ext.at("bufferView").get<size_t>());
  const size_t offset = view.value("byteOffset", size_t(0)),
               length = view.at("byteLength").get<size_t>();
  if (bin_at + offset + length > bytes.size()) return Fail("Draco buffer view beyond the file");

  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data() + bin_at + offset, length);
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok()) return Fail(std::string("Draco: ") + decoded.status().error_msg());
  draco::Mesh& mesh = *decoded.value();
  // KHR_draco_mesh_compression maps glTF attribute names to Draco unique ids.
  for (const auto& [name, id] : draco_ext.at("attributes").items()) {
    const draco::PointAttribute* att = mesh.GetAttributeByUniqueId(id.get<uint32_t>());
    if (!att)
      return Fail("no Draco attribute " + std::to_string(id.get<uint32_t>()) + " for " + name);
    if (att->attribute_type() != draco::GeometryAttribute::GENERIC) continue;
    auto metadata = std::make_unique<draco::AttributeMetadata>();
    metadata->AddEntryString(draco::GltfEncoder::kDracoMetadataGltfAttributeName, name);
    mesh.AddAttributeMetadata(mesh.GetAttributeIdByUniqueId(id.get<uint32_t>()),
                              std::move(metadata));
  }
  mesh.SetCompressionEnabled(false);
  draco::GltfEncoder encoder;
  const draco::Status status = encoder.EncodeFile(mesh, argv[2]);
  if (!status.ok()) return Fail(std::string(argv[2]) + ": " + status.error_msg());
  std::printf("%s: %u points, %u faces, %d attributes\n", argv[2], mesh.num_points(),
              unsigned(mesh.num_faces()), mesh.num_attributes());
  return 0;
}
