// libFuzzer target: RPC metadata text. The first byte picks the path:
//   0: "KEY: value" / "KEY=value" lines straight into RpcModel::FromKeyValues
//   1: the text as an _RPC.TXT sidecar of a tiny in-memory GeoTIFF, read by ReadRpc (GDAL)
//   2: the same as an .RPB sidecar
// A model that is accepted is then evaluated (projection, Jacobian, localisation): these
// must not crash, hang or hit undefined behaviour on any accepted coefficients.
#include <cpl_vsi.h>
#include <gdal_priv.h>

#include <map>
#include <string>

#include "core/common/error.h"
#include "core/common/gdal_init.h"
#include "core/rpc/rpc_io.h"
#include "core/rpc/rpc_model.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

using namespace satmesh;

std::map<std::string, std::string> ParseLines(const std::string& text) {
  std::map<std::string, std::string> md;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    const size_t sep = line.find_first_of(":=");
    if (sep != std::string::npos) md[line.substr(0, sep)] = line.substr(sep + 1);
    start = end + 1;
  }
  return md;
}

const char* kImage = "/vsimem/fuzz_rpc/img.tif";

void MakeImage() {
  EnsureGdalInitialized();
  CPLSetConfigOption("CPL_LOG", "/dev/null");
  CPLPushErrorHandler(CPLQuietErrorHandler);
  GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(kImage, 4, 4, 1, GDT_Byte, nullptr);
  GDALClose(GDALDataset::ToHandle(ds));
}

void Evaluate(const RpcModel& model) {
  const RpcCoefficients& c = model.coefficients();
  const Eigen::Vector3d at(c.long_off, c.lat_off, c.height_off);
  Eigen::Matrix<double, 2, 3> jacobian;
  (void)model.PixelFromGeo(at);
  (void)model.PixelFromGeo(at + Eigen::Vector3d(c.long_scale, c.lat_scale, c.height_scale) * 0.5, &jacobian);
  (void)model.LocalizeLonLat(Eigen::Vector2d(c.samp_off, c.line_off), c.height_off);
  (void)model.AtLevel(2).Cropped({10, 10}).WithBias({0.5, -0.5}).PixelFromGeo(at);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  MakeImage();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const int mode = data[0] % 3;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    if (mode == 0) {
      Evaluate(RpcModel::FromKeyValues(ParseLines(text)));
    } else {
      const std::string sidecar = mode == 1 ? "/vsimem/fuzz_rpc/img_RPC.TXT" : "/vsimem/fuzz_rpc/img.RPB";
      VSIFCloseL(VSIFileFromMemBuffer(sidecar.c_str(), const_cast<GByte*>(data + 1), vsi_l_offset(size - 1),
                                      /*bTakeOwnership=*/FALSE));
      try {
        Evaluate(ReadRpc(kImage));
      } catch (...) {
        VSIUnlink(sidecar.c_str());
        throw;
      }
      VSIUnlink(sidecar.c_str());
    }
  } catch (const Error& e) {
    if (e.code() != ErrorCode::kInvalidInput) fuzz::Fail(std::string("error code ") + ErrorCodeName(e.code()) + ": " + e.what());
  }
  return 0;
}
