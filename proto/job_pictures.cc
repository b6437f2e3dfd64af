#include "proto/job_pictures.h"

#include <cstdio>
#include <filesystem>

#include "core/dsm/dsm.h"

namespace satmesh::proto {

std::vector<PlotSeries> ConvergenceSeries(const nlohmann::json& metrics) {
  std::vector<PlotSeries> series;
  for (const auto& level : metrics.value("levels", nlohmann::json::array())) {
    PlotSeries s;
    char name[64];
    std::snprintf(name, sizeof(name), "level %d, GSD %.2f m", level.value("level", 0),
                  level.value("gsd_m", 0.0));
    s.name = name;
    s.y = level.value("mean_zncc", std::vector<double>{});
    if (!s.y.empty()) series.push_back(s);
  }
  return series;
}

std::vector<std::string> WriteJobPictures(const nlohmann::json& metrics,
                                          const std::string& out_dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> written;
  const fs::path dsm = fs::path(out_dir) / "dsm.tif";
  if (fs::exists(dsm)) {
    WriteHillshadePng((fs::path(out_dir) / "preview.png").string(), ReadDsm(dsm.string()));
    written.push_back("preview.png");
  }
  const auto series = ConvergenceSeries(metrics);
  if (!series.empty()) {
    WriteLinePlotPng((fs::path(out_dir) / "convergence.png").string(), series,
                     "photo-consistency per iteration", "iteration", "mean ZNCC");
    written.push_back("convergence.png");
  }
  return written;
}

}  // namespace satmesh::proto
