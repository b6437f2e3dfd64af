// `satmesh rpc project|localize`: evaluate an image's RPC (read through GDAL).
#include <cstdio>
#include <string>
#include <vector>

#include "client/args.h"
#include "client/command.h"
#include "core/common/error.h"
#include "core/rpc/rpc_io.h"

namespace satmesh::cli {
namespace {

constexpr const char* kUsage =
    "usage: satmesh rpc project  --image IMG.tif --lon DEG --lat DEG --h M\n"
    "       satmesh rpc localize --image IMG.tif --col PX --row PX --h M\n"
    "Pixels follow GDAL: (0,0) is the top-left corner of the top-left pixel.\n";

double RequireDouble(const Args& args, const std::string& key) {
  args.Require(key);
  return args.GetDouble(key, 0.0);
}

int RunRpc(const std::vector<std::string>& raw) {
  const Args args(raw, {"help"});
  if (args.Has("help") || args.positionals().size() != 1) {
    std::fputs(kUsage, args.Has("help") ? stdout : stderr);
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  const std::string& action = args.positionals()[0];
  if (action != "project" && action != "localize") {
    std::fprintf(stderr, "satmesh rpc: unknown action '%s'\n%s", action.c_str(), kUsage);
    return kExitUsage;
  }
  const std::string image = args.Require("image");
  const double h = RequireDouble(args, "h");
  if (action == "project") {
    const double lon = RequireDouble(args, "lon"), lat = RequireDouble(args, "lat");
    const Eigen::Vector2d px = ReadRpc(image).PixelFromGeo({lon, lat, h});
    std::printf("{\"col\": %.9f, \"row\": %.9f}\n", px.x(), px.y());
    return kExitOk;
  }
  const double col = RequireDouble(args, "col"), row = RequireDouble(args, "row");
  const auto lon_lat = ReadRpc(image).LocalizeLonLat({col, row}, h);
  SATMESH_CHECK(lon_lat.has_value(), ErrorCode::kNotConverged,
                "localisation of (" + std::to_string(col) + ", " + std::to_string(row) +
                    ") at h=" + std::to_string(h) + " in '" + image + "' did not converge");
  std::printf("{\"lon\": %.12f, \"lat\": %.12f, \"h\": %.6f}\n", lon_lat->x(), lon_lat->y(), h);
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("rpc", "project a point into an image or localise a pixel (RPC)", RunRpc);

}  // namespace satmesh::cli
