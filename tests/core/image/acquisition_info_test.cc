// Acquisition metadata: the IMD keys of WorldView and Pléiades as GDAL exposes them, ISO
// 8601 times, and the round trip through a GeoTIFF's IMD domain.
#include "core/image/acquisition_info.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "core/image/image_io.h"
#include "tests/scratch_dir.h"

namespace satmesh {
namespace {

TEST(ParseIso8601Utc, WorldViewAndPleiadesForms) {
  // 2015-10-26 = day 16734 since 1970-01-01.
  EXPECT_EQ(DaysFromCivil(2015, 10, 26), 16734);
  EXPECT_NEAR(*ParseIso8601Utc("2015-10-26T16:21:45.123456Z"), 16734 * 86400.0 + 58905.123456, 1e-6);
  EXPECT_NEAR(*ParseIso8601Utc("2015-10-26 16:21:45"), 16734 * 86400.0 + 58905, 1e-9);
  EXPECT_NEAR(*ParseIso8601Utc("2015-10-26T18:21:45+02:00"), 16734 * 86400.0 + 58905, 1e-9);
  EXPECT_FALSE(ParseIso8601Utc("26/10/2015 16:21").has_value());
  EXPECT_FALSE(ParseIso8601Utc("2015-13-26T16:21:45Z").has_value());
  EXPECT_EQ(FormatIso8601Utc(16734 * 86400.0 + 58905.5), "2015-10-26T16:21:45.500000Z");
  EXPECT_EQ(FormatIso8601Utc(0), "1970-01-01T00:00:00.000000Z");
}

TEST(AcquisitionInfoFromMetadata, WorldViewImdKeys) {
  const AcquisitionInfo a = AcquisitionInfoFromMetadata({
      {"IMAGE_1.satId", "\"WV03\";"},
      {"IMAGE_1.firstLineTime", "2015-10-26T16:21:45.123456Z;"},
      {"IMAGE_1.meanSunAz", "155.3"},
      {"IMAGE_1.meanSunEl", "42.5"},
      {"IMAGE_1.meanSatAz", "210.1"},
      {"IMAGE_1.meanSatEl", "71.0"},
      {"IMAGE_1.meanOffNadirViewAngle", "17.1"},
      {"IMAGE_2.meanSunEl", "12.0"},  // a second image listed: IMAGE_1 wins
  });
  EXPECT_DOUBLE_EQ(*a.sun_elevation_deg, 42.5);
  EXPECT_DOUBLE_EQ(*a.sun_azimuth_deg, 155.3);
  EXPECT_DOUBLE_EQ(*a.satellite_elevation_deg, 71.0);
  EXPECT_DOUBLE_EQ(*a.satellite_azimuth_deg, 210.1);
  EXPECT_DOUBLE_EQ(*a.off_nadir_deg, 17.1);
  EXPECT_NEAR(*a.acquisition_unix_s, 16734 * 86400.0 + 58905.123456, 1e-6);
}

TEST(AcquisitionInfoFromMetadata, PleiadesDimKeysAndAbsentOnes) {
  const std::string g = "Geometric_Data.Use_Area.Located_Geometric_Values.";
  const AcquisitionInfo p = AcquisitionInfoFromMetadata({
      {g + "Solar_Incidences.SUN_ELEVATION", "61.2"},
      {g + "Solar_Incidences.SUN_AZIMUTH", "148.7"},
      {g + "Acquisition_Angles.INCIDENCE_ANGLE", "12.0"},
      {g + "Acquisition_Angles.VIEWING_ANGLE", "10.5"},
      {"Dataset_Sources.Source_Identification.Strip_Source.IMAGING_DATE", "2013-07-19"},
      {"Dataset_Sources.Source_Identification.Strip_Source.IMAGING_TIME", "10:41:17.5Z"},
  });
  EXPECT_DOUBLE_EQ(*p.sun_elevation_deg, 61.2);
  EXPECT_DOUBLE_EQ(*p.sun_azimuth_deg, 148.7);
  EXPECT_DOUBLE_EQ(*p.satellite_elevation_deg, 78.0);
  EXPECT_DOUBLE_EQ(*p.off_nadir_deg, 10.5);
  EXPECT_FALSE(p.satellite_azimuth_deg.has_value());
  EXPECT_NEAR(*p.acquisition_unix_s, DaysFromCivil(2013, 7, 19) * 86400.0 + 38477.5, 1e-6);

  const AcquisitionInfo none = AcquisitionInfoFromMetadata({{"IMAGE_1.meanSunEl", "n/a"}, {"AREA_OR_POINT", "Area"}});
  EXPECT_TRUE(none.empty());
}

TEST(ReadAcquisitionInfo, RoundTripsThroughTheGeoTiffImdDomain) {
  GDALAllRegister();
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("satmesh_acq_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  testing::RemoveAtExit(dir);
  AcquisitionInfo in;
  in.sun_elevation_deg = 38.25, in.sun_azimuth_deg = 141.5, in.satellite_elevation_deg = 66.5;
  in.satellite_azimuth_deg = 301.25, in.off_nadir_deg = 21.125;
  in.acquisition_unix_s = 1.4501e9 + 0.25;
  const std::string path = (dir / "imd.tif").string();
  GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(path.c_str(), 4, 4, 1, GDT_UInt16, nullptr);
  ASSERT_NE(ds, nullptr);
  char** md = nullptr;
  for (const auto& [k, v] : ImdMetadata(in)) md = CSLSetNameValue(md, k.c_str(), v.c_str());
  EXPECT_EQ(CSLCount(md), 6);
  EXPECT_EQ(ds->SetMetadata(md, "IMD"), CE_None);
  CSLDestroy(md);
  GDALClose(ds);
  // GDAL itself gives the domain back after reopening (GTiff keeps it in GDAL_METADATA).
  GDALDataset* re = GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY);
  ASSERT_NE(re, nullptr);
  EXPECT_STREQ(re->GetMetadataItem("IMAGE_1.meanSunEl", "IMD"), "38.250000");
  EXPECT_STREQ(re->GetMetadataItem("IMAGE_1.firstLineTime", "IMD"), "2015-12-14T13:33:20.250000Z");
  GDALClose(re);
  const AcquisitionInfo out = ReadAcquisitionInfo(path);
  EXPECT_DOUBLE_EQ(*out.sun_elevation_deg, 38.25);
  EXPECT_DOUBLE_EQ(*out.sun_azimuth_deg, 141.5);
  EXPECT_DOUBLE_EQ(*out.satellite_elevation_deg, 66.5);
  EXPECT_DOUBLE_EQ(*out.satellite_azimuth_deg, 301.25);
  EXPECT_DOUBLE_EQ(*out.off_nadir_deg, 21.125);
  EXPECT_NEAR(*out.acquisition_unix_s, 1.4501e9 + 0.25, 1e-6);
  // A file without acquisition metadata: nothing set.
  const std::string plain = (dir / "plain.tif").string();
  GDALClose(GetGDALDriverManager()->GetDriverByName("GTiff")->Create(plain.c_str(), 2, 2, 1, GDT_Byte, nullptr));
  EXPECT_TRUE(ReadAcquisitionInfo(plain).empty());
}

}  // namespace
}  // namespace satmesh
