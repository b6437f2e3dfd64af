#include "core/mesh/mesh.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/common/error.h"
#include "tests/core/mesh/mesh_fixtures.h"

namespace satmesh {
namespace {

std::string ValidateMessage(const TriangleMesh& mesh) {
  try {
    ValidateMesh(mesh, "tile.ply");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidInput);
    return e.what();
  }
  return "";
}

TEST(ValidateMesh, AcceptsValidMesh) { EXPECT_EQ(ValidateMessage(testing::CreateCube()), ""); }

TEST(ValidateMesh, RejectsNaNVertex) {
  TriangleMesh mesh = testing::CreateCube();
  mesh.vertices[5].y() = NAN;
  const std::string msg = ValidateMessage(mesh);
  EXPECT_NE(msg.find("tile.ply"), std::string::npos) << msg;
  EXPECT_NE(msg.find("vertex 5"), std::string::npos) << msg;
}

TEST(ValidateMesh, RejectsOutOfRangeIndex) {
  TriangleMesh mesh = testing::CreateCube();
  mesh.faces[3][1] = 8;
  const std::string msg = ValidateMessage(mesh);
  EXPECT_NE(msg.find("face 3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("index 8"), std::string::npos) << msg;
  mesh.faces[3][1] = -1;
  EXPECT_NE(ValidateMessage(mesh).find("index -1"), std::string::npos);
}

TEST(TriangleMesh, AbsoluteVertexAddsOriginInDouble) {
  TriangleMesh mesh;
  mesh.origin = {435123.0, 5421000.0, 250.0};
  mesh.vertices.emplace_back(0.456789f, -1.25f, 3.5f);
  const Eigen::Vector3d p = mesh.AbsoluteVertex(0);
  EXPECT_NEAR(p.x(), 435123.456789, 1e-7);
  EXPECT_DOUBLE_EQ(p.y(), 5420998.75);
  EXPECT_DOUBLE_EQ(p.z(), 253.5);
}

}  // namespace
}  // namespace satmesh
