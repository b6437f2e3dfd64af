// Inputs the fuzz targets found (tests/fuzz/corpus/*/crash-*), read by the normal build:
// each is refused with Error{kInvalidInput} naming the file and the problem. (The HTTP
// one is a case of tests/server/malformed_test.cc.)
#include <gtest/gtest.h>

#include <string>

#include "core/common/error.h"
#include "core/image/image_io.h"
#include "core/mesh/mesh_io.h"

namespace satmesh {
namespace {

std::string Refusal(const std::string& corpus_file) {
  const std::string path = std::string(SATMESH_SOURCE_DIR) + "/tests/fuzz/corpus/" + corpus_file;
  try {
    ReadMesh(path);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidInput) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    return e.what();
  }
  return "(read without error)";
}

// fuzz_ply: a face index of 1.4e91 was converted to long long (undefined behaviour).
TEST(FuzzRegression, PlyVertexIndexBeyondLongLong) {
  const std::string message = Refusal("ply/crash-index-1e91-cast-overflow.ply");
  EXPECT_NE(message.find("out of range"), std::string::npos) << message;
}

// fuzz_ply: an element of 3.3e9 rows without properties looped for minutes.
TEST(FuzzRegression, PlyElementOfBillionsOfEmptyRows) {
  const std::string message = Refusal("ply/crash-timeout-3e9-empty-rows.ply");
  EXPECT_NE(message.find("3344244444"), std::string::npos) << message;
}

// fuzz_drc: 48 bytes declaring ~2e8 faces made Draco allocate 2.9 GB before failing.
TEST(FuzzRegression, DracoCountsBeyondWhatTheStreamCanEncode) {
  const std::string message = Refusal("drc/crash-oom-declares-2e8-faces.drc");
  EXPECT_NE(message.find("more than it can encode"), std::string::npos) << message;
}

// fuzz_drc (second round): an old 1.x bitstream with fixed-size counts, also gigabytes.
TEST(FuzzRegression, DracoBitstreamBefore22) {
  const std::string message = Refusal("drc/crash-oom-bitstream-1.253.drc");
  EXPECT_NE(message.find("bitstream version 1.253 is not supported"), std::string::npos) << message;
}

// fuzz_drc (third round): 111 bytes whose header flags metadata, then counts that made
// Draco allocate 3 GB (the count check had skipped streams with metadata).
TEST(FuzzRegression, DracoCountsAfterMetadata) {
  const std::string message = Refusal("drc/crash-oom-metadata-then-3e9-bytes.drc");
  EXPECT_NE(message.find("more than it can encode"), std::string::npos) << message;
}

// fuzz_drc: a position attribute of type bool made Draco read arbitrary bytes as bool.
TEST(FuzzRegression, DracoPositionsOfTypeBool) {
  const std::string message = Refusal("drc/crash-bool-position-attribute.drc");
  EXPECT_NE(message.find("not a number type"), std::string::npos) << message;
}

// fuzz_geotiff: a 1 KB TIFF of 8x8 pixels declaring 12,033 pixel-interleaved bands made
// GDAL allocate a 3 GB block for one pixel.
TEST(FuzzRegression, TiffWhoseOneBlockWouldTakeGigabytes) {
  const std::string path =
      std::string(SATMESH_SOURCE_DIR) + "/tests/fuzz/corpus/geotiff/crash-oom-12033-interleaved-bands.tif";
  try {
    ReadImageWindow(path, 1, PixelWindow{0, 0, 4, 4});
    FAIL() << "read without error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidInput);
    EXPECT_NE(std::string(e.what()).find("interleaved bands is 3008 MB (at most 256 MB"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace satmesh
