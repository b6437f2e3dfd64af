#include <gtest/gtest.h>

#include <fstream>

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

TEST(JobSpecFromJson, ReadsAnInitialMeshWithItsCrsAndTheDsmResolution) {
  json job = MinimalJob();
  job["initial"] = {{"mesh", "runs/a/"}, {"crs", "EPSG:4978"}};
  job["outputs"] = {{"dsm_resolution_m", 0.5}};
  const JobSpec spec = proto::JobSpecFromJson(job, "/base");
  EXPECT_EQ(spec.initial_mesh.path, "/base/runs/a/");
  EXPECT_EQ(spec.initial_mesh.crs, "EPSG:4978");
  EXPECT_TRUE(spec.initial_dsm.empty());
  EXPECT_EQ(spec.dsm_resolution_m, 0.5);
  job["initial"]["dsm"] = "dsm.tif";  // both: the DSM fills where the mesh has no surface
  EXPECT_EQ(proto::JobSpecFromJson(job, "/base").initial_dsm, "/base/dsm.tif");
}

TEST(JobSpecFromJson, InitialNeedsADsmOrAMesh) {
  json job = MinimalJob();
  job["initial"] = json::object();
  EXPECT_NE(ErrorOf(job).find("initial: needs dsm or mesh"), std::string::npos) << ErrorOf(job);
  job["initial"] = {{"dsm", "dsm.tif"}, {"crs", "EPSG:4326"}};
  EXPECT_NE(ErrorOf(job).find("initial.crs: is the initial mesh's CRS"), std::string::npos) << ErrorOf(job);
  job["initial"] = {{"mesh", ""}};
  EXPECT_NE(ErrorOf(job).find("initial.mesh: expected a non-empty string"), std::string::npos) << ErrorOf(job);
  job["initial"] = {{"mesh", "m.ply"}};
  job["outputs"] = {{"dsm_resolution_m", -1}};
  EXPECT_NE(ErrorOf(job).find("outputs.dsm_resolution_m must be >= 0"), std::string::npos) << ErrorOf(job);
}

TEST(JobSpecFromJson, ReadsHowOftenHitMapsAreMadeAnew) {
  json job = MinimalJob();
  EXPECT_EQ(proto::JobSpecFromJson(job, "/base").refine.hit_maps_every, 2);
  job["options"]["hit_maps_every"] = 1;
  EXPECT_EQ(proto::JobSpecFromJson(job, "/base").refine.hit_maps_every, 1);
  job["options"]["hit_maps_every"] = 21;
  EXPECT_NE(ErrorOf(job).find("options.hit_maps_every must be in [1, 20], got 21"), std::string::npos)
      << ErrorOf(job);
}

TEST(JobSpecFromJson, ReadsThePairSelectionAndConfidenceOptions) {
  json job = MinimalJob();
  job["options"]["min_pair_angle_deg"] = 3;
  job["options"]["max_pair_angle_deg"] = 45;
  job["options"]["optimal_pair_angle_deg"] = 15;
  job["options"]["min_pair_overlap"] = 0.5;
  job["options"]["pair_partners_per_view"] = 2;
  job["options"]["max_pairs"] = 20;
  job["options"]["min_height_confidence"] = 0.2;
  job["options"]["hold_unseen"] = false;
  job["options"]["noise_variance_factor"] = 0;
  job["options"]["levels"] = -1;
  job["options"]["max_coarse_edge_m"] = 3;
  const RefineOptions o = proto::JobSpecFromJson(job, "/base").refine;
  EXPECT_EQ(o.pairs.min_angle_deg, 3);
  EXPECT_EQ(o.pairs.max_angle_deg, 45);
  EXPECT_EQ(o.pairs.optimal_angle_deg, 15);
  EXPECT_EQ(o.pairs.min_overlap, 0.5);
  EXPECT_EQ(o.pairs.partners_per_view, 2);
  EXPECT_EQ(o.pairs.max_pairs, 20);
  EXPECT_EQ(o.min_height_confidence, 0.2);
  EXPECT_FALSE(o.hold_unseen);
  EXPECT_EQ(o.noise_variance_factor, 0);
  EXPECT_EQ(o.levels, -1);
  EXPECT_EQ(o.max_coarse_edge_m, 3);
  job["options"]["optimal_pair_angle_deg"] = 50;  // above max_pair_angle_deg
  EXPECT_NE(ErrorOf(job).find("options.optimal_pair_angle_deg must be in [min_pair_angle_deg, max_pair_angle_deg]"), std::string::npos) << ErrorOf(job);
  job["options"]["optimal_pair_angle_deg"] = 15;
  job["options"]["min_height_confidence"] = 0;
  EXPECT_NE(ErrorOf(job).find("min_height_confidence"), std::string::npos) << ErrorOf(job);
}

TEST(ResolveLevels, CoarseEdgeStaysUnderTheBound) {
  RefineOptions o;  // levels -1, coarse edge 2 px, bound 2 m
  EXPECT_EQ(ResolveLevels(o, 0.3, 0.3), 1);   // 1.2 m (2.4 m at L = 2)
  EXPECT_EQ(ResolveLevels(o, 0.5, 0.5), 1);   // 2.0 m
  EXPECT_EQ(ResolveLevels(o, 0.7, 0.5), 0);   // 1.4 m; 2.8 m at L = 1
  EXPECT_EQ(ResolveLevels(o, 0.3, 2.0), 1);   // a 2 m DSM: the bound is its cell
  EXPECT_EQ(ResolveLevels(o, 0.3, 5.0), 3);   // a 5 m DSM: 4.8 m, capped at 3
  EXPECT_EQ(ResolveLevels(o, 0.1, 0.1), 3);
  // A mesh start carries its coarse levels (carry_coarse_levels -1): one coarser level up
  // to twice the bound, never more than a DSM start otherwise.
  EXPECT_EQ(ResolveLevels(o, 0.503, 0.503), 0);        // 2.01 m at L = 1
  EXPECT_EQ(ResolveLevels(o, 0.503, 0.503, true), 1);
  EXPECT_EQ(ResolveLevels(o, 0.7, 0.5, true), 1);      // 2.8 m <= 4 m
  EXPECT_EQ(ResolveLevels(o, 1.2, 1.0, true), 0);      // 4.8 m > 4 m
  EXPECT_EQ(ResolveLevels(o, 0.3, 0.3, true), 1);      // as a DSM start
  o.carry_coarse_levels = 0;
  EXPECT_EQ(ResolveLevels(o, 0.7, 0.5, true), 0);
  o.carry_coarse_levels = 1;
  EXPECT_EQ(ResolveLevels(o, 0.7, 0.5, false), 1);
  o.levels = 2;
  EXPECT_EQ(ResolveLevels(o, 0.5, 0.5), 2);   // the user's choice stands
}

TEST(JobSpecFromJson, ReadsAoiAndTiling) {
  json job = MinimalJob();
  job["aoi"] = {{"bbox", {10, 20, 110, 220}}, {"crs", "EPSG:32617"}};
  job["tiling"] = {{"size_m", 100}, {"overlap_m", 12.5}, {"workers", 3}, {"memory_budget_mb", 4096}};
  JobSpec spec = proto::JobSpecFromJson(job, "/base");
  ASSERT_EQ(spec.aoi.polygon.size(), 4u);
  EXPECT_EQ(spec.aoi.polygon[2], Eigen::Vector2d(110, 220));
  EXPECT_EQ(spec.aoi.crs, "EPSG:32617");
  EXPECT_EQ(spec.tiling.tile_size_m, 100);
  EXPECT_EQ(spec.tiling.overlap_m, 12.5);
  EXPECT_EQ(spec.tiling.workers, 3);
  EXPECT_EQ(spec.tiling.memory_budget_mb, 4096);
  job["aoi"] = {{"polygon", {{0, 0}, {5, 0}, {0, 5}}}};
  spec = proto::JobSpecFromJson(job, "/base");
  EXPECT_EQ(spec.aoi.polygon.size(), 3u);
  EXPECT_EQ(spec.aoi.crs, "");
}

TEST(JobSpecFromJson, BadTilingFieldsAreNamed) {
  json job = MinimalJob();
  job["tiling"] = {{"workers", 0}};
  EXPECT_NE(ErrorOf(job).find("tiling.workers"), std::string::npos) << ErrorOf(job);
  job["tiling"] = {{"memory_budget_mb", -1}};
  EXPECT_NE(ErrorOf(job).find("tiling.memory_budget_mb"), std::string::npos) << ErrorOf(job);
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

// A value of the option other than its default that Check() accepts.
json NonDefaultValue(const RefineOptionInfo& option) {
  const OptionValue d = option.Default();
  if (const bool* b = std::get_if<bool>(&d)) return !*b;
  const double x = std::holds_alternative<int>(d) ? std::get<int>(d) : std::get<double>(d);
  for (const double v : {x + 1, x - 1, x / 2, x * 1.5, x + 0.5, x + 2}) {
    RefineOptions o;
    option.Set(&o, option.type() == OptionType::kInt ? OptionValue(int(v)) : OptionValue(v));
    if (o.Check().empty() && option.Get(o) != d)
      return option.type() == OptionType::kInt ? json(int(v)) : json(v);
  }
  ADD_FAILURE() << option.name << ": no valid value other than the default tried";
  return nullptr;
}

TEST(JobSpecFromJson, EveryRefinementOptionRoundTrips) {
  for (const RefineOptionInfo& option : RefineOptionTable()) {
    json job = MinimalJob();
    job["options"][std::string(option.name)] = NonDefaultValue(option);
    const RefineOptions read = proto::JobSpecFromJson(job, "/base").refine;
    EXPECT_EQ(json(std::visit([](auto v) { return json(v); }, option.Get(read))),
              job["options"][std::string(option.name)])
        << option.name;
    EXPECT_NE(option.Get(read), option.Default()) << option.name;
  }
}

TEST(JobSpecFromJson, OutOfRangeOptionsAreNamedWithTheirRange) {
  for (const RefineOptionInfo& option : RefineOptionTable()) {
    const std::string path = "options." + std::string(option.name);
    json job = MinimalJob();
    const OptionRange& r = option.range;
    const bool integer = option.type() == OptionType::kInt;
    for (const double v : {r.min ? *r.min - 1 : NAN, r.max ? *r.max + 1 : NAN}) {
      if (std::isnan(v)) continue;
      job["options"][std::string(option.name)] = integer ? json(int(v)) : json(v);
      const std::string error = ErrorOf(job);
      EXPECT_EQ(error.find(path + " must be "), 0u) << error;
      EXPECT_NE(error.find(option.RangeText()), std::string::npos) << error;
    }
    // The wrong JSON type.
    job["options"][std::string(option.name)] = option.type() == OptionType::kBool ? json(1) : json("2");
    EXPECT_EQ(ErrorOf(job).find(path + ": expected "), 0u) << ErrorOf(job);
  }
  json job = MinimalJob();
  job["options"]["pairs.min_angle_deg"] = 3;  // a struct path is not a wire name
  EXPECT_EQ(ErrorOf(job), "options.pairs.min_angle_deg: unknown option");
}

// The schema file's `section` properties are the table's (proto::*OptionsSchema()).
void ExpectSchemaSectionIs(const std::string& section, const json& expected) {
  std::ifstream in(std::string(SATMESH_PROTO_DIR) + "/job.schema.json");
  const json properties = json::parse(in)["properties"][section]["properties"];
  for (const auto& [name, schema] : expected.items())
    EXPECT_EQ(properties.value(name, json()), schema)
        << "job.schema.json " << section << "." << name << " should read\n\"" << name << "\": " << schema.dump();
  for (const auto& [name, schema] : properties.items())
    EXPECT_TRUE(expected.contains(name)) << "job.schema.json " << section << "." << name << " is not in the table";
}

TEST(JobSchema, OptionsAndTilingAreTheTables) {
  ExpectSchemaSectionIs("options", proto::RefineOptionsSchema());
  ExpectSchemaSectionIs("tiling", proto::TilingOptionsSchema());
}

TEST(JobSpecFromJson, OutOfRangeTilingIsNamedWithItsRange) {
  for (const TilingOptionInfo& option : TilingOptionTable()) {
    json job = MinimalJob();
    job["tiling"][std::string(option.name)] = -1;
    const std::string error = ErrorOf(job);
    EXPECT_EQ(error.find("tiling." + std::string(option.name) + " must be "), 0u) << error;
    EXPECT_NE(error.find(option.RangeText() + ", got -1"), std::string::npos) << error;
  }
}

TEST(ApplyOptionOverride, RefinementOptionsAreTheTables) {
  json job = MinimalJob();
  proto::ApplyOptionOverride(&job, "options.min_pair_angle_deg=3");
  proto::ApplyOptionOverride(&job, "hold_unseen=false");
  EXPECT_EQ(job["options"]["min_pair_angle_deg"], 3);
  EXPECT_EQ(job["options"]["hold_unseen"], false);
  EXPECT_THROW(proto::ApplyOptionOverride(&job, "tiling.size=3"), Error);
  try {
    proto::ApplyOptionOverride(&job, "min_angle_deg=3");
    ADD_FAILURE() << "an unknown option was set";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--set min_angle_deg: unknown option"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("min_pair_angle_deg"), std::string::npos) << e.what();
  }
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
