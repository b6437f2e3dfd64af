#include <gtest/gtest.h>

#include "core/common/error.h"
#include "proto/job_spec_json.h"

namespace satmesh {
namespace {

using nlohmann::json;

json MinimalJob() {
  return json::parse(R"({"images": [{"href": "a.tif"}, {"href": "/abs/b.tif"}],
                         "initial": {"dsm": "initial/dsm.tif"}})");
}

std::string ErrorOf(const json& job) {
  try {
    proto::JobSpecFromJson(job, "/base");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(JobSpecFromJson, JobWithoutTilingIsOneTileOverTheDsm) {
  const JobSpec spec = proto::JobSpecFromJson(MinimalJob(), "/base");
  EXPECT_EQ(spec.images[0].path, "/base/a.tif");
  EXPECT_EQ(spec.images[1].path, "/abs/b.tif");
  EXPECT_EQ(spec.initial_dsm, "/base/initial/dsm.tif");
  EXPECT_TRUE(spec.aoi.polygon.empty());
  EXPECT_EQ(spec.tiling.tile_size_m, 0);
  EXPECT_EQ(spec.tiling.workers, 1);
  EXPECT_EQ(spec.fill_holes_m, 50);
}

TEST(JobSpecFromJson, ReadsTheHoleFillingDistance) {
  json job = MinimalJob();
  job["initial"]["fill_holes_m"] = 0;
  EXPECT_EQ(proto::JobSpecFromJson(job, "/base").fill_holes_m, 0);
  job["initial"]["fill_holes_m"] = 1e5;
  EXPECT_NE(ErrorOf(job).find("initial.fill_holes_m"), std::string::npos) << ErrorOf(job);
}

TEST(JobSpecFromJson, ReadsHowOftenHitMapsAreMadeAnew) {
  json job = MinimalJob();
  EXPECT_EQ(proto::JobSpecFromJson(job, "/base").refine.hit_maps_every, 2);
  job["options"]["hit_maps_every"] = 1;
  EXPECT_EQ(proto::JobSpecFromJson(job, "/base").refine.hit_maps_every, 1);
  job["options"]["hit_maps_every"] = 21;
  EXPECT_NE(ErrorOf(job).find("hit_maps_every must be in [1, 20]"), std::string::npos)
      << ErrorOf(job);
}

TEST(JobSpecFromJson, ReadsAoiAndTiling) {
  json job = MinimalJob();
  job["aoi"] = {{"bbox", {10, 20, 110, 220}}, {"crs", "EPSG:32617"}};
  job["tiling"] = {{"size_m", 100}, {"overlap_m", 12.5}, {"workers", 3}};
  JobSpec spec = proto::JobSpecFromJson(job, "/base");
  ASSERT_EQ(spec.aoi.polygon.size(), 4u);
  EXPECT_EQ(spec.aoi.polygon[2], Eigen::Vector2d(110, 220));
  EXPECT_EQ(spec.aoi.crs, "EPSG:32617");
  EXPECT_EQ(spec.tiling.tile_size_m, 100);
  EXPECT_EQ(spec.tiling.overlap_m, 12.5);
  EXPECT_EQ(spec.tiling.workers, 3);
  job["aoi"] = {{"polygon", {{0, 0}, {5, 0}, {0, 5}}}};
  spec = proto::JobSpecFromJson(job, "/base");
  EXPECT_EQ(spec.aoi.polygon.size(), 3u);
  EXPECT_EQ(spec.aoi.crs, "");
}

TEST(JobSpecFromJson, BadTilingFieldsAreNamed) {
  json job = MinimalJob();
  job["tiling"] = {{"workers", 0}};
  EXPECT_NE(ErrorOf(job).find("tiling.workers"), std::string::npos) << ErrorOf(job);
  job["tiling"] = {{"size", 10}};
  EXPECT_NE(ErrorOf(job).find("tiling.size: unknown field"), std::string::npos) << ErrorOf(job);
  job = MinimalJob();
  job["aoi"] = {{"bbox", {10, 20, 5, 220}}};
  EXPECT_NE(ErrorOf(job).find("aoi.bbox"), std::string::npos) << ErrorOf(job);
  job["aoi"] = {{"bbox", {0, 0, 1, 1}}, {"polygon", {{0, 0}, {5, 0}, {0, 5}}}};
  EXPECT_NE(ErrorOf(job).find("exactly one"), std::string::npos) << ErrorOf(job);
  job["aoi"] = {{"polygon", {{0, 0}, {5, 0}}}};
  EXPECT_NE(ErrorOf(job).find("aoi.polygon"), std::string::npos) << ErrorOf(job);
}

TEST(ApplyOptionOverride, DottedKeysSetTopLevelObjects) {
  json job = MinimalJob();
  proto::ApplyOptionOverride(&job, "tiling.size_m=150");
  proto::ApplyOptionOverride(&job, "levels=2");
  EXPECT_EQ(job["tiling"]["size_m"], 150);
  EXPECT_EQ(job["options"]["levels"], 2);
  EXPECT_EQ(proto::JobSpecFromJson(job, "/b").tiling.tile_size_m, 150);
  proto::ApplyOptionOverride(&job, R"(aoi={"bbox": [0, 0, 10, 10]})");
  EXPECT_EQ(proto::JobSpecFromJson(job, "/b").aoi.polygon.size(), 4u);
}

}  // namespace
}  // namespace satmesh
