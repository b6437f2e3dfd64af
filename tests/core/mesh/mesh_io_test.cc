#include "core/mesh/mesh_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/common/error.h"
#include "tests/core/mesh/mesh_fixtures.h"
#include "tests/scratch_dir.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

std::string TempPath(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("satmesh_mesh_io_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  testing::RemoveAtExit(dir);
  return (dir / name).string();
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void Spit(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// A wavy grid at UTM magnitude whose bounding-box centre rounds to its own origin, so a
// PLY/OBJ reader (which re-centres on the rounded bbox centre) must return it bit-exactly.
TriangleMesh UtmMesh(int n = 10) {
  TriangleMesh mesh = testing::CreateGridMesh(n, 1.5f, /*wavy=*/true);
  float zlo = INFINITY, zhi = -INFINITY;
  for (const auto& v : mesh.vertices) zlo = std::min(zlo, v.z()), zhi = std::max(zhi, v.z());
  const Eigen::Vector3f shift(0.75f * n, 0.75f * n, 0.5f * (zlo + zhi));
  for (auto& v : mesh.vertices) v = v - shift + Eigen::Vector3f(0.000123f, 0, 0);
  mesh.origin = {435123.0, 5421987.0, 251.0};
  mesh.crs = "EPSG:32631";
  return mesh;
}

// Error message of ReadMesh(path), checking the code; "" when it did not throw.
std::string ReadError(const std::string& path, ErrorCode code = ErrorCode::kInvalidInput) {
  try {
    ReadMesh(path);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    return e.what();
  }
  return "";
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(MeshWriteOptions, DefaultsAreValid) { EXPECT_EQ(MeshWriteOptions{}.Check(), ""); }

TEST(MeshWriteOptions, InvalidValuesRejected) {
  MeshWriteOptions options;
  options.draco_position_bits = 31;
  EXPECT_TRUE(Contains(options.Check(), "draco_position_bits"));
  EXPECT_THROW(WriteMesh(TempPath("bad.drc"), testing::CreateCube(), options), Error);
  options = {};
  options.draco_speed = -1;
  EXPECT_TRUE(Contains(options.Check(), "draco_speed"));
}

TEST(WriteMesh, BinaryDoublePlyHoldsExactAbsoluteCoordinates) {
  TriangleMesh mesh;
  mesh.origin = {435123.0, 5421000.0, 250.0};
  mesh.vertices = {{0.456789f, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  const std::string path = TempPath("exact.ply");
  WriteMesh(path, mesh);
  const std::string bytes = Slurp(path);
  const size_t data = bytes.find("end_header\n") + 11;
  ASSERT_EQ(bytes.size(), data + 3 * 24 + 13);  // one buffered pass, nothing extra
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      double value;
      std::memcpy(&value, bytes.data() + data + 24 * i + 8 * k, 8);
      EXPECT_EQ(value, mesh.AbsoluteVertex(i)[k]);  // bit-exact: origin + double(vertex)
    }
}

TEST(ReadMesh, AsciiDoublePlyKeepsUtmDigits) {
  const std::string path = TempPath("utm_ascii.ply");
  Spit(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
             "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n435123.456789 5421987.654321 251.25\n435124.5 5421987.5 250.75\n"
             "435123.5 5421988.5 251\n3 0 1 2\n");
  const TriangleMesh mesh = ReadMesh(path);
  EXPECT_EQ(mesh.origin, Eigen::Vector3d(435124, 5421988, 251));
  EXPECT_NEAR(mesh.AbsoluteVertex(0).x(), 435123.456789, 1e-7);
  EXPECT_NEAR(mesh.AbsoluteVertex(0).y(), 5421987.654321, 1e-7);
  EXPECT_NEAR(mesh.AbsoluteVertex(0).z(), 251.25, 1e-7);
}

struct PlyCase {
  bool binary, dbl;
};

TEST(ReadMesh, PlyRoundTripsAllEncodings) {
  const TriangleMesh mesh = UtmMesh();
  for (const PlyCase c : {PlyCase{true, true}, PlyCase{false, true}, PlyCase{true, false},
                          PlyCase{false, false}}) {
    SCOPED_TRACE(std::string(c.binary ? "binary " : "ascii ") + (c.dbl ? "double" : "float"));
    MeshWriteOptions options;
    options.ply_binary = c.binary;
    options.ply_double = c.dbl;
    const std::string path = TempPath("roundtrip.ply");
    WriteMesh(path, mesh, options);
    const TriangleMesh back = ReadMesh(path);
    EXPECT_EQ(back.faces, mesh.faces);
    EXPECT_EQ(back.crs, "EPSG:32631");
    ASSERT_EQ(back.num_vertices(), mesh.num_vertices());
    if (c.dbl) {
      EXPECT_EQ(back.origin, mesh.origin);
      EXPECT_EQ(back.vertices, mesh.vertices);  // bit-exact
    } else {
      for (size_t i = 0; i < mesh.num_vertices(); ++i)
        for (int k = 0; k < 3; ++k) {
          const double truth = mesh.AbsoluteVertex(i)[k];
          // Absolute coordinates stored as float: half an ulp at UTM magnitude.
          EXPECT_NEAR(back.AbsoluteVertex(i)[k], truth, std::abs(truth) * 0x1p-24 + 1e-6);
        }
    }
  }
}

// Little-endian binary PLY body builder for hand-made files.
struct Bytes {
  std::string s;
  template <typename T>
  Bytes& operator<<(T v) {
    s.append(reinterpret_cast<const char*>(&v), sizeof(T));
    return *this;
  }
};

TEST(ReadMesh, PlySkipsExtraPropertiesAndElementsAndTriangulatesPolygons) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment colours and normals\n"
      "element vertex 4\nproperty float nx\nproperty double x\nproperty float y\n"
      "property uchar red\nproperty float z\nproperty list uchar int extra\n"
      "element face 1\nproperty uchar flags\nproperty list int uint vertex_index\n"
      "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
  Bytes body;
  const float xyz[4][3] = {{0, 0, 0}, {2, 0, 0}, {2, 2, 1}, {0, 2, 1}};
  for (int i = 0; i < 4; ++i) {
    body << 0.5f << double(xyz[i][0]) << xyz[i][1] << uint8_t(200) << xyz[i][2];
    body << uint8_t(2) << int32_t(7) << int32_t(8);
  }
  body << uint8_t(1) << int32_t(4) << uint32_t(0) << uint32_t(1) << uint32_t(2) << uint32_t(3);
  body << int32_t(0) << int32_t(1);
  const std::string path = TempPath("extras.ply");
  Spit(path, header + body.s);
  const TriangleMesh mesh = ReadMesh(path);
  ASSERT_EQ(mesh.num_vertices(), 4u);
  ASSERT_EQ(mesh.num_faces(), 2u);
  EXPECT_EQ(mesh.faces[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(mesh.faces[1], Eigen::Vector3i(0, 2, 3));
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(mesh.AbsoluteVertex(i), Eigen::Vector3d(xyz[i][0], xyz[i][1], xyz[i][2]));
}

class MalformedPly : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = TempPath("valid.ply");
    WriteMesh(path_, UtmMesh(4));  // 25 vertices, 32 faces
    bytes_ = Slurp(path_);
    data_ = bytes_.find("end_header\n") + 11;
  }
  std::string path_, bytes_;
  size_t data_ = 0;
};

TEST_F(MalformedPly, TruncatedBinaryRejected) {
  const std::string path = TempPath("truncated.ply");
  Spit(path, bytes_.substr(0, bytes_.size() - 5));
  const std::string msg = ReadError(path);
  EXPECT_TRUE(Contains(msg, "truncated")) << msg;
  EXPECT_TRUE(Contains(msg, "'face' row 31 of 32")) << msg;
  Spit(path, bytes_.substr(0, data_ + 100));  // inside the vertices
  EXPECT_TRUE(Contains(ReadError(path), "'vertex' row 4 of 25"));
}

TEST_F(MalformedPly, HeaderFaceCountMismatchRejected) {
  std::string fewer = bytes_, more = bytes_;
  fewer.replace(fewer.find("element face 32"), 15, "element face 31");
  more.replace(more.find("element face 32"), 15, "element face 33");
  const std::string path = TempPath("count.ply");
  Spit(path, fewer);
  std::string msg = ReadError(path);
  EXPECT_TRUE(Contains(msg, "do not match")) << msg;
  Spit(path, more);
  msg = ReadError(path);
  EXPECT_TRUE(Contains(msg, "truncated") && Contains(msg, "row 32 of 33")) << msg;
}

TEST_F(MalformedPly, NaNVertexRejected) {
  std::string bytes = bytes_;
  const double nan = NAN;
  std::memcpy(bytes.data() + data_ + 24 * 7 + 8, &nan, 8);  // vertex 7, y
  const std::string path = TempPath("nan.ply");
  Spit(path, bytes);
  std::string msg = ReadError(path);
  EXPECT_TRUE(Contains(msg, "vertex 7 has a non-finite coordinate")) << msg;
  Spit(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
  msg = ReadError(path);
  EXPECT_TRUE(Contains(msg, "vertex 1 has a non-finite coordinate")) << msg;
}

TEST_F(MalformedPly, IndexOutOfRangeRejected) {
  std::string bytes = bytes_;
  const int32_t bad = 25;
  std::memcpy(bytes.data() + data_ + 24 * 25 + 13 * 3 + 1 + 4, &bad, 4);  // face 3, corner 1
  const std::string path = TempPath("index.ply");
  Spit(path, bytes);
  const std::string msg = ReadError(path);
  EXPECT_TRUE(Contains(msg, "face 3 has vertex index 25 out of range [0, 25)")) << msg;
}

TEST(ReadMesh, PlyFaceElementWithoutIndexListRejected) {
  const std::string path = TempPath("noindices.ply");
  Spit(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar int corners\n"
             "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_TRUE(Contains(ReadError(path), "no 'vertex_indices'"));
}

TEST(ReadMesh, MissingFileAndUnknownExtension) {
  ReadError("/nonexistent/mesh.ply", ErrorCode::kNotFound);
  ReadError(TempPath("mesh.stl"), ErrorCode::kInvalidArgument);
  EXPECT_THROW(WriteMesh(TempPath("mesh.stl"), testing::CreateCube()), Error);
  EXPECT_THROW(WriteMesh("/nonexistent/dir/mesh.ply", testing::CreateCube()), Error);
}

TEST(ReadMesh, ObjRoundTripIsExact) {
  const TriangleMesh mesh = UtmMesh();
  const std::string path = TempPath("roundtrip.obj");
  WriteMesh(path, mesh);
  const TriangleMesh back = ReadMesh(path);
  EXPECT_EQ(back.origin, mesh.origin);
  EXPECT_EQ(back.vertices, mesh.vertices);
  EXPECT_EQ(back.faces, mesh.faces);
  EXPECT_EQ(back.crs, mesh.crs);
}

TEST(ReadMesh, ObjSlashFormsNegativeIndicesAndPolygons) {
  const std::string path = TempPath("forms.obj");
  Spit(path, "# a quad and a triangle\r\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\n"
             "vn 0 0 1\nusemtl x\nf 1/1/1 2/1/1 3//1 4\nv 2 2 2\nf -1 -3 -2\n");
  const TriangleMesh mesh = ReadMesh(path);
  ASSERT_EQ(mesh.num_vertices(), 5u);
  ASSERT_EQ(mesh.num_faces(), 3u);
  EXPECT_EQ(mesh.faces[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(mesh.faces[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(mesh.faces[2], Eigen::Vector3i(4, 2, 3));
  Spit(path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 4\n");
  EXPECT_TRUE(Contains(ReadError(path), "face on line 4 has vertex index 3 out of range"));
  Spit(path, "v 0 0 0\nv 1 nan 0\nv 1 1 0\nf 1 2 3\n");
  EXPECT_TRUE(Contains(ReadError(path), "vertex 1 has a non-finite coordinate"));
}

// Draco reorders vertices: map each decoded vertex to its nearest original, check the
// distance bound, then check the mapped faces (up to rotation) equal the original faces.
void ExpectSameMeshUpToOrder(const TriangleMesh& truth, const TriangleMesh& back, double tol) {
  ASSERT_EQ(back.num_faces(), truth.num_faces());
  EXPECT_EQ(back.origin, Eigen::Vector3d::Zero());
  std::vector<int> map(back.num_vertices());
  double worst = 0;
  for (size_t i = 0; i < back.num_vertices(); ++i) {
    double best = INFINITY;
    for (size_t j = 0; j < truth.num_vertices(); ++j) {
      const double d = (back.vertices[i] - truth.vertices[j]).cwiseAbs().maxCoeff();
      if (d < best) best = d, map[i] = int(j);
    }
    worst = std::max(worst, best);
  }
  EXPECT_LE(worst, tol);
  const auto canonical = [](Eigen::Vector3i f) {
    while (f[0] != f.minCoeff()) f = Eigen::Vector3i(f[1], f[2], f[0]);
    return std::array<int, 3>{f[0], f[1], f[2]};
  };
  std::vector<std::array<int, 3>> a, b;
  for (const auto& f : truth.faces) a.push_back(canonical(f));
  for (const auto& f : back.faces) b.push_back(canonical({map[f[0]], map[f[1]], map[f[2]]}));
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  EXPECT_EQ(a, b);
}

TEST(ReadMesh, DracoRoundTripWithinQuantisation) {
  const TriangleMesh mesh = UtmMesh(20);
  double extent = 0;  // largest bbox side, metres
  for (int k = 0; k < 3; ++k) {
    float lo = INFINITY, hi = -INFINITY;
    for (const auto& v : mesh.vertices) lo = std::min(lo, v[k]), hi = std::max(hi, v[k]);
    extent = std::max(extent, double(hi - lo));
  }
  for (const std::string ext : {".drc", ".glb"}) {
    for (int bits : {16, 20}) {
      SCOPED_TRACE(ext + " " + std::to_string(bits) + " bits");
      MeshWriteOptions options;
      options.draco_position_bits = bits;
      const std::string path = TempPath("roundtrip" + ext);
      WriteMesh(path, mesh, options);
      ExpectSameMeshUpToOrder(mesh, ReadMesh(path), extent / std::ldexp(1.0, bits));
    }
  }
}

TEST(ReadMesh, CorruptDracoAndGlbRejected) {
  const std::string drc = TempPath("corrupt.drc"), glb = TempPath("corrupt.glb");
  WriteMesh(drc, UtmMesh(4));
  WriteMesh(glb, UtmMesh(4));
  Spit(drc, Slurp(drc).substr(0, 20));
  Spit(glb, Slurp(glb).substr(0, 40));
  EXPECT_TRUE(Contains(ReadError(drc), "Draco"));
  EXPECT_TRUE(Contains(ReadError(glb), "GLB"));
  Spit(glb, "not a glb at all");
  EXPECT_TRUE(Contains(ReadError(glb), "glTF magic"));
}

TEST(WriteGlb, CarriesNormalsAndNamedScalarsDracoCompressed) {
  const TriangleMesh mesh = UtmMesh(6);
  std::vector<float> height(mesh.num_vertices());
  for (size_t i = 0; i < height.size(); ++i) height[i] = mesh.vertices[i].z();
  const std::string path = TempPath("scalars.glb");
  WriteGlb(path, mesh, {{"_HEIGHT", height}});
  const std::string bytes = Slurp(path);
  uint32_t json_length = 0;
  std::memcpy(&json_length, bytes.data() + 12, 4);
  const std::string json = bytes.substr(20, json_length);
  // Both in the primitive's attributes and in its Draco extension's attribute map.
  for (const std::string name : {"\"NORMAL\"", "\"_HEIGHT\"", "\"POSITION\""}) {
    const size_t first = json.find(name);
    ASSERT_NE(first, std::string::npos) << name << " in " << json;
    EXPECT_NE(json.find(name, first + 1), std::string::npos) << name << " twice in " << json;
  }
  EXPECT_TRUE(Contains(json, "KHR_draco_mesh_compression"));
  // The reader still reads the positions.
  EXPECT_EQ(ReadMesh(path).num_vertices(), mesh.num_vertices());
}

TEST(WriteGlb, BadScalarsRejectedWithTheirName) {
  const TriangleMesh mesh = UtmMesh(4);
  const std::string path = TempPath("bad_scalars.glb");
  const auto error = [&](const VertexScalar& s) {
    try {
      WriteGlb(path, mesh, {s});
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_TRUE(Contains(error({"height", std::vector<float>(mesh.num_vertices())}), "'height'"));
  EXPECT_TRUE(Contains(error({"_HEIGHT", std::vector<float>(3)}), "has 3 values for"));
  std::vector<float> nan(mesh.num_vertices(), 0.f);
  nan[2] = NAN;
  EXPECT_TRUE(Contains(error({"_HEIGHT", nan}), "not finite at vertex 2"));
}

// The refinement's per-vertex height sigma survives PLY in every encoding, +inf (no image
// saw the vertex) included; a mesh without it is written without the property.
TEST(ReadMesh, PlyKeepsHeightSigma) {
  TriangleMesh mesh = UtmMesh();
  for (size_t i = 0; i < mesh.num_vertices(); ++i) mesh.height_sigma.push_back(0.01f * float(i + 1));
  mesh.height_sigma.back() = std::numeric_limits<float>::infinity();
  for (const bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    MeshWriteOptions options;
    options.ply_binary = binary;
    const std::string path = TempPath("sigma.ply");
    WriteMesh(path, mesh, options);
    const TriangleMesh back = ReadMesh(path);
    ASSERT_EQ(back.height_sigma.size(), mesh.num_vertices());
    EXPECT_EQ(back.height_sigma, mesh.height_sigma);  // shortest round-trip text is exact
    EXPECT_EQ(back.AbsoluteVertex(1), mesh.AbsoluteVertex(1));
  }
  const std::string plain = TempPath("plain.ply");
  WriteMesh(plain, UtmMesh());
  EXPECT_EQ(Slurp(plain).find("height_sigma"), std::string::npos);
  EXPECT_TRUE(ReadMesh(plain).height_sigma.empty());
}

}  // namespace
}  // namespace satmesh
