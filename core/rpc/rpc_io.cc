#include "core/rpc/rpc_io.h"

#include <cpl_string.h>
#include <gdal.h>

#include <map>

#include "core/common/error.h"
#include "core/common/gdal_init.h"

namespace satmesh {

RpcModel ReadRpc(const std::string& image_path) {
  EnsureGdalInitialized();
  GDALDatasetH ds = GDALOpen(image_path.c_str(), GA_ReadOnly);
  SATMESH_CHECK(ds != nullptr, ErrorCode::kNotFound, "cannot open image '" + image_path + "'");
  std::map<std::string, std::string> md;
  for (CSLConstList item = GDALGetMetadata(ds, "RPC"); item && *item; ++item) {
    char* key = nullptr;
    const char* value = CPLParseNameValue(*item, &key);
    if (key != nullptr && value != nullptr) md[key] = value;
    CPLFree(key);
  }
  GDALClose(ds);
  SATMESH_CHECK(!md.empty(), ErrorCode::kInvalidInput,
                "image '" + image_path + "' has no RPC (GDAL metadata domain \"RPC\" is empty)");
  try {
    return RpcModel::FromKeyValues(md);
  } catch (const Error& e) {
    ThrowError(e.code(), "image '" + image_path + "': " + e.what());
  }
}

}  // namespace satmesh
