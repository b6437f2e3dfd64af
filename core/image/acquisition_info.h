#pragma once
// Acquisition metadata of a satellite image (sun and satellite angles, time), as the
// vendors deliver it (WorldView .IMD/.XML, Pléiades DIM) and GDAL exposes it: the "IMD"
// metadata domain ("IMAGE_1.meanSunEl", ...) and the "IMAGERY" domain
// ("ACQUISITIONDATETIME"). No GDAL types here; the file reader is in image_io.h.
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace satmesh {

struct AcquisitionInfo {
  std::optional<double> sun_elevation_deg;        // above the horizon
  std::optional<double> sun_azimuth_deg;          // clockwise from north
  std::optional<double> satellite_elevation_deg;  // of the satellite seen from the scene
  std::optional<double> satellite_azimuth_deg;    // clockwise from north
  std::optional<double> off_nadir_deg;            // at the satellite
  std::optional<double> acquisition_unix_s;       // first line time, UTC seconds since 1970
  bool empty() const {
    return !sun_elevation_deg && !sun_azimuth_deg && !satellite_elevation_deg &&
           !satellite_azimuth_deg && !off_nadir_deg && !acquisition_unix_s;
  }
};

using MetadataList = std::vector<std::pair<std::string, std::string>>;

// Parses metadata items of the IMD (and IMAGERY) domains. Keys are matched on their last
// '.'-separated component, case-insensitively, preferring IMAGE_1 where several images
// are listed:
//   WorldView IMD: meanSunEl, meanSunAz, meanSatEl, meanSatAz, meanOffNadirViewAngle,
//     firstLineTime (else earliestAcqTime);
//   Pléiades DIM: SUN_ELEVATION, SUN_AZIMUTH, VIEWING_ANGLE (off-nadir),
//     INCIDENCE_ANGLE (90 - satellite elevation), AZIMUTH_ANGLE, IMAGING_DATE + IMAGING_TIME;
//   GDAL IMAGERY: ACQUISITIONDATETIME.
// Absent or unparsable values stay unset.
AcquisitionInfo AcquisitionInfoFromMetadata(const MetadataList& items);

// The WorldView IMD items ("IMAGE_1.meanSunEl", ..., "IMAGE_1.firstLineTime") for the
// set fields of `info`, values as the IMD writes them (degrees, ISO 8601 UTC).
MetadataList ImdMetadata(const AcquisitionInfo& info);

// "2015-03-14T15:56:12.345678Z" (microseconds, UTC).
std::string FormatIso8601Utc(double unix_s);
// Parses "YYYY-MM-DD[T ]hh:mm:ss[.ffffff][Z|+00:00]" (UTC); nullopt if malformed.
std::optional<double> ParseIso8601Utc(const std::string& text);
// Days since 1970-01-01 of a proleptic Gregorian date.
long long DaysFromCivil(int year, int month, int day);

}  // namespace satmesh
