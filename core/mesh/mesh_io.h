#pragma once
// Mesh files: PLY (ASCII/binary, float/double vertices), OBJ, Draco (.drc), glTF binary
// (.glb with KHR_draco_mesh_compression). The format follows the file extension.
#include <string>
#include <vector>

#include "core/mesh/mesh.h"

namespace satmesh {

struct MeshWriteOptions {
  bool ply_binary = true;          // PLY: binary little endian (else ASCII)
  bool ply_double = true;          // PLY: vertex x,y,z as double (origin added)
  int draco_position_bits = 16;    // Draco/glb position quantisation, in [8, 30]
  // Draco encoder speed, in [0, 10] (0 = best ratio). 6 encodes a stereo 0.5 m tile's glb
  // in 0.24 s against 5's 0.32 s at the same size (2.47 MB); 7 is 0.5% larger, 8 11%.
  int draco_speed = 6;
  // glb normals and per-vertex scalars: gltf-pipeline's defaults (8 and 12 bits); a tile
  // of 33.8k vertices: 129 KB positions only, 247 KB with normals, _HEIGHT and _CHANGE.
  int draco_normal_bits = 8;       // glb normals' quantisation (octahedral), in [6, 16]
  int draco_scalar_bits = 12;      // glb per-vertex scalars' quantisation, in [8, 24]

  std::string Check() const;  // "" or a message naming the bad field
};

// A per-vertex value written into a .glb as an application-specific glTF attribute
// (name "_UPPER_CASE", e.g. "_HEIGHT"; float, one per vertex, Draco-compressed).
struct VertexScalar {
  std::string name;
  std::vector<float> values;
};

// PLY/OBJ: absolute coordinates (origin + vertex) written in double where the format
// allows. DRC/GLB: positions written tile-local (vertices only; origin is the caller's
// transform, e.g. in tileset.json). GLB also carries per-vertex normals (area-weighted
// face normals, Draco-compressed like the positions) so that viewers shade it. Throws Error naming the file on failure:
// kInvalidArgument for bad options or an unknown extension, kInvalidInput for an
// invalid mesh (ValidateMesh), kIo when the file cannot be written.
void WriteMesh(const std::string& path, const TriangleMesh& mesh,
               const MeshWriteOptions& options = {});
// A .glb with extra per-vertex scalars (each of mesh.num_vertices() finite values; a
// name not of the form "_[A-Z0-9_]+" or a wrong count throws kInvalidArgument).
void WriteGlb(const std::string& path, const TriangleMesh& mesh,
              const std::vector<VertexScalar>& scalars, const MeshWriteOptions& options = {});

// Reads by extension. PLY/OBJ: origin is set to the bounding-box centre (rounded to
// metres) so vertices stay tile-local floats. Truncated or inconsistent files, NaN
// coordinates and out-of-range indices throw Error{kInvalidInput} naming the file.
// PLY: ascii / binary little or big endian; any scalar type for x, y, z (other vertex
// properties are skipped); faces from "vertex_indices" or "vertex_index" lists; other
// elements skipped. PLY/OBJ polygons are fan-triangulated. OBJ: v and f lines (v/vt/vn
// forms, negative indices). DRC/GLB: origin 0, positions as stored. A "crs" comment
// written by WriteMesh (PLY/OBJ) is read back into mesh.crs.
TriangleMesh ReadMesh(const std::string& path);

}  // namespace satmesh
