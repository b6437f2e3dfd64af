#pragma once
// Reading RPCs through GDAL: GeoTIFF RPC tags, .RPB, _RPC.TXT, NITF RPC00B — anything
// GDAL exposes in its "RPC" metadata domain.
#include <string>

#include "core/rpc/rpc_model.h"

namespace satmesh {

// Throws Error{kNotFound} if the file cannot be opened, Error{kInvalidInput} if it
// has no (or a malformed) RPC; the message names the file and the field.
RpcModel ReadRpc(const std::string& image_path);

}  // namespace satmesh
