#include "core/image/acquisition_info.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>

namespace satmesh {
namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::optional<double> ParseNumber(const std::string& text) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (end == begin || !std::isfinite(v)) return std::nullopt;
  while (*end == ' ' || *end == ';' || *end == '"') ++end;
  return *end == '\0' ? std::optional<double>(v) : std::nullopt;
}

std::string Unquote(std::string s) {
  while (!s.empty() && (s.back() == ';' || s.back() == ' ' || s.back() == '"')) s.pop_back();
  size_t k = 0;
  while (k < s.size() && (s[k] == ' ' || s[k] == '"')) ++k;
  return s.substr(k);
}

// A field set from the best-ranked key seen: rank 0 for IMAGE_1 or unindexed keys,
// 1 for other images.
struct Best {
  std::string value;
  int rank = 2;
  void Offer(const std::string& v, int r) {
    if (r < rank) value = v, rank = r;
  }
  bool set() const { return rank < 2; }
};

}  // namespace

long long DaysFromCivil(int y, int m, int d) {
  y -= m <= 2;
  const long long era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = unsigned(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + (long long)doe - 719468;
}

std::string FormatIso8601Utc(double unix_s) {
  const double whole = std::floor(unix_s);
  long long micro = std::llround((unix_s - whole) * 1e6);
  long long secs = (long long)whole;
  if (micro >= 1000000) micro -= 1000000, ++secs;
  long long days = secs >= 0 ? secs / 86400 : (secs - 86399) / 86400;
  const long long sod = secs - days * 86400;
  // Civil from days (Howard Hinnant's algorithm).
  days += 719468;
  const long long era = (days >= 0 ? days : days - 146096) / 146097;
  const unsigned doe = unsigned(days - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  const unsigned d = doy - (153 * mp + 2) / 5 + 1;
  const unsigned m = mp < 10 ? mp + 3 : mp - 9;
  const long long y = (long long)yoe + era * 400 + (m <= 2);
  char buf[96];  // room for any year and the compiler's worst case
  std::snprintf(buf, sizeof(buf), "%04lld-%02u-%02uT%02lld:%02lld:%02lld.%06lldZ", y, m, d, sod / 3600,
                sod / 60 % 60, sod % 60, micro);
  return buf;
}

std::optional<double> ParseIso8601Utc(const std::string& raw) {
  const std::string text = Unquote(raw);
  int y, mo, d, h, mi, n = 0;
  char sep;
  if (std::sscanf(text.c_str(), "%4d-%2d-%2d%c%2d:%2d%n", &y, &mo, &d, &sep, &h, &mi, &n) != 6 || n == 0)
    return std::nullopt;
  if ((sep != 'T' && sep != ' ') || mo < 1 || mo > 12 || d < 1 || d > 31 || h > 23 || mi > 59)
    return std::nullopt;
  double sec = 0;
  size_t k = size_t(n);
  if (k < text.size() && text[k] == ':') {
    const char* begin = text.c_str() + k + 1;
    char* end = nullptr;
    sec = std::strtod(begin, &end);
    if (end == begin || sec < 0 || sec >= 61) return std::nullopt;
    k = size_t(end - text.c_str());
  }
  double offset_s = 0;
  const std::string zone = text.substr(k);
  if (!zone.empty() && zone != "Z") {
    int zh = 0, zm = 0;
    if ((zone[0] != '+' && zone[0] != '-') || std::sscanf(zone.c_str() + 1, "%2d:%2d", &zh, &zm) != 2)
      return std::nullopt;
    offset_s = (zone[0] == '+' ? 1 : -1) * (zh * 3600.0 + zm * 60.0);
  }
  return double(DaysFromCivil(y, mo, d)) * 86400 + h * 3600.0 + mi * 60.0 + sec - offset_s;
}

AcquisitionInfo AcquisitionInfoFromMetadata(const MetadataList& items) {
  std::map<std::string, Best> by_name;  // lower-case last key component -> value
  for (const auto& [key, value] : items) {
    const size_t dot = key.rfind('.');
    const std::string name = Lower(dot == std::string::npos ? key : key.substr(dot + 1));
    const std::string upper_key = Lower(key);
    const bool other_image = upper_key.rfind("image_", 0) == 0 && upper_key.rfind("image_1.", 0) != 0;
    by_name[name].Offer(Unquote(value), other_image ? 1 : 0);
  }
  auto number = [&](std::initializer_list<const char*> names) -> std::optional<double> {
    for (const char* n : names) {
      auto it = by_name.find(n);
      if (it != by_name.end() && it->second.set())
        if (auto v = ParseNumber(it->second.value)) return v;
    }
    return std::nullopt;
  };
  auto text = [&](const char* n) -> std::optional<std::string> {
    auto it = by_name.find(n);
    if (it == by_name.end() || !it->second.set()) return std::nullopt;
    return it->second.value;
  };
  AcquisitionInfo info;
  info.sun_elevation_deg = number({"meansunel", "sun_elevation"});
  info.sun_azimuth_deg = number({"meansunaz", "sun_azimuth"});
  info.satellite_elevation_deg = number({"meansatel"});
  if (!info.satellite_elevation_deg)
    if (auto incidence = number({"incidence_angle"})) info.satellite_elevation_deg = 90 - *incidence;
  info.satellite_azimuth_deg = number({"meansataz", "azimuth_angle"});
  info.off_nadir_deg = number({"meanoffnadirviewangle", "viewing_angle"});
  for (const char* n : {"firstlinetime", "earliestacqtime", "acquisitiondatetime"})
    if (auto t = text(n); t && !info.acquisition_unix_s) info.acquisition_unix_s = ParseIso8601Utc(*t);
  if (!info.acquisition_unix_s) {
    auto date = text("imaging_date"), time = text("imaging_time");
    if (date && time) info.acquisition_unix_s = ParseIso8601Utc(*date + "T" + *time);
  }
  return info;
}

MetadataList ImdMetadata(const AcquisitionInfo& info) {
  MetadataList items;
  auto put = [&](const char* name, const std::optional<double>& v) {
    if (!v) return;
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.6f", *v);
    items.emplace_back(std::string("IMAGE_1.") + name, buf);
  };
  put("meanSunEl", info.sun_elevation_deg);
  put("meanSunAz", info.sun_azimuth_deg);
  put("meanSatEl", info.satellite_elevation_deg);
  put("meanSatAz", info.satellite_azimuth_deg);
  put("meanOffNadirViewAngle", info.off_nadir_deg);
  if (info.acquisition_unix_s)
    items.emplace_back("IMAGE_1.firstLineTime", FormatIso8601Utc(*info.acquisition_unix_s));
  return items;
}

}  // namespace satmesh
