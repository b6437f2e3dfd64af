#include "core/rpc/rpc_model.h"

#include <Eigen/LU>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <algorithm>
#include <sstream>

#include "core/common/error.h"

namespace satmesh {
namespace {

constexpr int kTerms = 20;
using Terms = std::array<double, kTerms>;

// The 20 RPC00B monomials of normalised (L, P, H), term order as in the header.
inline void Monomials(double l, double p, double h, Terms* m) {
  Terms& t = *m;
  t[0] = 1.0;       t[1] = l;         t[2] = p;         t[3] = h;
  t[4] = l * p;     t[5] = l * h;     t[6] = p * h;     t[7] = l * l;
  t[8] = p * p;     t[9] = h * h;     t[10] = p * l * h; t[11] = l * l * l;
  t[12] = l * p * p; t[13] = l * h * h; t[14] = l * l * p; t[15] = p * p * p;
  t[16] = p * h * h; t[17] = l * l * h; t[18] = p * p * h; t[19] = h * h * h;
}

// Gradient of one cubic w.r.t. (L, P, H), reusing the monomials m (lp = m[4], lh = m[5],
// ph = m[6], ll = m[7], pp = m[8], hh = m[9]).
inline void CubicGradient(const std::array<double, kTerms>& c, const Terms& m, double l, double p,
                          double h, double g[3]) {
  g[0] = c[1] + c[4] * p + c[5] * h + 2 * c[7] * l + c[10] * m[6] + 3 * c[11] * m[7] +
         c[12] * m[8] + c[13] * m[9] + 2 * c[14] * m[4] + 2 * c[17] * m[5];
  g[1] = c[2] + c[4] * l + c[6] * h + 2 * c[8] * p + c[10] * m[5] + 2 * c[12] * m[4] +
         c[14] * m[7] + 3 * c[15] * m[8] + c[16] * m[9] + 2 * c[18] * m[6];
  g[2] = c[3] + c[5] * l + c[6] * p + 2 * c[9] * h + c[10] * m[4] + 2 * c[13] * m[5] +
         2 * c[16] * m[6] + c[17] * m[7] + c[18] * m[8] + 3 * c[19] * m[9];
}

inline double Dot(const std::array<double, kTerms>& c, const Terms& m) {
  double s = 0.0;
  for (int i = 0; i < kTerms; ++i) s += c[i] * m[i];
  return s;
}

void CheckFinite(double v, const char* field) {
  SATMESH_CHECK(std::isfinite(v), ErrorCode::kInvalidInput,
                std::string("RPC field ") + field + " is not finite");
}

void CheckScale(double v, const char* field) {
  CheckFinite(v, field);
  SATMESH_CHECK(v != 0.0, ErrorCode::kInvalidInput,
                std::string("RPC field ") + field + " is zero (a scale must be non-zero)");
}

// Parses a number; with allow_unit, a trailing unit word as in _RPC.TXT ("+0.5 pixels").
double ParseNumber(const std::string& text, const std::string& key, bool allow_unit) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  bool ok = end != begin;
  if (ok && !allow_unit) ok = *end == '\0';
  if (ok) {
    for (const char* c = end; *c; ++c) {
      if (!std::isalpha(static_cast<unsigned char>(*c)) &&
          !std::isspace(static_cast<unsigned char>(*c))) {
        ok = false;
        break;
      }
    }
  }
  SATMESH_CHECK(ok, ErrorCode::kInvalidInput,
                "RPC key " + key + ": cannot parse a number from '" + text + "'");
  SATMESH_CHECK(std::isfinite(v), ErrorCode::kInvalidInput,
                "RPC key " + key + ": value '" + text + "' is not finite");
  return v;
}

const std::string& Lookup(const std::map<std::string, std::string>& md, const std::string& key) {
  auto it = md.find(key);
  SATMESH_CHECK(it != md.end(), ErrorCode::kInvalidInput, "RPC key " + key + " is missing");
  return it->second;
}

std::array<double, kTerms> ParseCoefficients(const std::map<std::string, std::string>& md,
                                             const std::string& key) {
  const std::string& text = Lookup(md, key);
  std::istringstream in(text);
  std::array<double, kTerms> out{};
  std::string token;
  int n = 0;
  while (in >> token) {
    SATMESH_CHECK(n < kTerms, ErrorCode::kInvalidInput,
                  "RPC key " + key + ": more than 20 coefficients");
    out[n] = ParseNumber(token, key + "[" + std::to_string(n) + "]", /*allow_unit=*/false);
    ++n;
  }
  SATMESH_CHECK(n == kTerms, ErrorCode::kInvalidInput,
                "RPC key " + key + ": expected 20 coefficients, found " + std::to_string(n));
  return out;
}

std::string FormatNumber(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

std::string FormatCoefficients(const std::array<double, kTerms>& c) {
  std::string s;
  for (int i = 0; i < kTerms; ++i) {
    if (i > 0) s += ' ';
    s += FormatNumber(c[i]);
  }
  return s;
}

}  // namespace

RpcModel RpcModel::FromCoefficients(const RpcCoefficients& c) {
  CheckFinite(c.line_off, "LINE_OFF");
  CheckFinite(c.samp_off, "SAMP_OFF");
  CheckFinite(c.lat_off, "LAT_OFF");
  CheckFinite(c.long_off, "LONG_OFF");
  CheckFinite(c.height_off, "HEIGHT_OFF");
  CheckScale(c.line_scale, "LINE_SCALE");
  CheckScale(c.samp_scale, "SAMP_SCALE");
  CheckScale(c.lat_scale, "LAT_SCALE");
  CheckScale(c.long_scale, "LONG_SCALE");
  CheckScale(c.height_scale, "HEIGHT_SCALE");
  const std::pair<const std::array<double, kTerms>*, const char*> polys[] = {
      {&c.line_num, "LINE_NUM_COEFF"}, {&c.line_den, "LINE_DEN_COEFF"},
      {&c.samp_num, "SAMP_NUM_COEFF"}, {&c.samp_den, "SAMP_DEN_COEFF"}};
  for (const auto& [poly, name] : polys) {
    for (int i = 0; i < kTerms; ++i) {
      SATMESH_CHECK(std::isfinite((*poly)[i]), ErrorCode::kInvalidInput,
                    std::string("RPC field ") + name + "[" + std::to_string(i) +
                        "] is not finite");
    }
  }
  SATMESH_CHECK(c.line_den[0] != 0.0, ErrorCode::kInvalidInput,
                "RPC field LINE_DEN_COEFF[0] (denominator constant term) is zero");
  SATMESH_CHECK(c.samp_den[0] != 0.0, ErrorCode::kInvalidInput,
                "RPC field SAMP_DEN_COEFF[0] (denominator constant term) is zero");
  RpcModel model;
  model.coefficients_ = c;
  return model;
}

RpcModel RpcModel::FromKeyValues(const std::map<std::string, std::string>& md) {
  RpcCoefficients c;
  const std::pair<double*, const char*> scalars[] = {
      {&c.line_off, "LINE_OFF"},     {&c.samp_off, "SAMP_OFF"},
      {&c.lat_off, "LAT_OFF"},       {&c.long_off, "LONG_OFF"},
      {&c.height_off, "HEIGHT_OFF"}, {&c.line_scale, "LINE_SCALE"},
      {&c.samp_scale, "SAMP_SCALE"}, {&c.lat_scale, "LAT_SCALE"},
      {&c.long_scale, "LONG_SCALE"}, {&c.height_scale, "HEIGHT_SCALE"}};
  for (const auto& [field, key] : scalars) *field = ParseNumber(Lookup(md, key), key, /*allow_unit=*/true);
  c.line_num = ParseCoefficients(md, "LINE_NUM_COEFF");
  c.line_den = ParseCoefficients(md, "LINE_DEN_COEFF");
  c.samp_num = ParseCoefficients(md, "SAMP_NUM_COEFF");
  c.samp_den = ParseCoefficients(md, "SAMP_DEN_COEFF");
  return FromCoefficients(c);
}

std::map<std::string, std::string> RpcModel::ToKeyValues() const {
  const RpcCoefficients& c = coefficients_;
  return {{"LINE_OFF", FormatNumber(c.line_off)},
          {"SAMP_OFF", FormatNumber(c.samp_off)},
          {"LAT_OFF", FormatNumber(c.lat_off)},
          {"LONG_OFF", FormatNumber(c.long_off)},
          {"HEIGHT_OFF", FormatNumber(c.height_off)},
          {"LINE_SCALE", FormatNumber(c.line_scale)},
          {"SAMP_SCALE", FormatNumber(c.samp_scale)},
          {"LAT_SCALE", FormatNumber(c.lat_scale)},
          {"LONG_SCALE", FormatNumber(c.long_scale)},
          {"HEIGHT_SCALE", FormatNumber(c.height_scale)},
          {"LINE_NUM_COEFF", FormatCoefficients(c.line_num)},
          {"LINE_DEN_COEFF", FormatCoefficients(c.line_den)},
          {"SAMP_NUM_COEFF", FormatCoefficients(c.samp_num)},
          {"SAMP_DEN_COEFF", FormatCoefficients(c.samp_den)}};
}

// GDAL's RPC transformer (3.6, verified in rpc_gdal_test) returns
// pixel = SAMP + 0.5, line = LINE + 0.5 (pixel-is-area), without DEM; we match it.
Eigen::Vector2d RpcModel::PixelFromGeo(const Eigen::Vector3d& lon_lat_h) const {
  const RpcCoefficients& c = coefficients_;
  const double l = (lon_lat_h.x() - c.long_off) / c.long_scale;
  const double p = (lon_lat_h.y() - c.lat_off) / c.lat_scale;
  const double h = (lon_lat_h.z() - c.height_off) / c.height_scale;
  Terms m;
  Monomials(l, p, h, &m);
  const double samp = Dot(c.samp_num, m) / Dot(c.samp_den, m) * c.samp_scale + c.samp_off;
  const double line = Dot(c.line_num, m) / Dot(c.line_den, m) * c.line_scale + c.line_off;
  return {(samp + 0.5 + bias_.x() - window_origin_.x()) * scale_,
          (line + 0.5 + bias_.y() - window_origin_.y()) * scale_};
}

Eigen::Vector2d RpcModel::PixelFromGeo(const Eigen::Vector3d& lon_lat_h,
                                       Eigen::Matrix<double, 2, 3>* jacobian) const {
  if (jacobian == nullptr) return PixelFromGeo(lon_lat_h);
  const RpcCoefficients& c = coefficients_;
  const double l = (lon_lat_h.x() - c.long_off) / c.long_scale;
  const double p = (lon_lat_h.y() - c.lat_off) / c.lat_scale;
  const double h = (lon_lat_h.z() - c.height_off) / c.height_scale;
  Terms m;
  Monomials(l, p, h, &m);
  const double inv_norm[3] = {1.0 / c.long_scale, 1.0 / c.lat_scale, 1.0 / c.height_scale};
  // Quotient rule: d(n/d) = (n' d - n d') / d^2, chained through the normalisations.
  auto ratio = [&](const std::array<double, kTerms>& num, const std::array<double, kTerms>& den,
                   double out_scale, double* value, double* grad) {
    const double n = Dot(num, m), d = Dot(den, m);
    double dn[3], dd[3];
    CubicGradient(num, m, l, p, h, dn);
    CubicGradient(den, m, l, p, h, dd);
    const double inv_d = 1.0 / d;
    *value = n / d;  // as in the plain overload, bit for bit
    for (int k = 0; k < 3; ++k) {
      grad[k] = (dn[k] * d - n * dd[k]) * inv_d * inv_d * inv_norm[k] * out_scale;
    }
  };
  double samp_n, line_n, dsamp[3], dline[3];
  ratio(c.samp_num, c.samp_den, c.samp_scale * scale_, &samp_n, dsamp);
  ratio(c.line_num, c.line_den, c.line_scale * scale_, &line_n, dline);
  for (int k = 0; k < 3; ++k) {
    (*jacobian)(0, k) = dsamp[k];
    (*jacobian)(1, k) = dline[k];
  }
  const double samp = samp_n * c.samp_scale + c.samp_off;
  const double line = line_n * c.line_scale + c.line_off;
  return {(samp + 0.5 + bias_.x() - window_origin_.x()) * scale_,
          (line + 0.5 + bias_.y() - window_origin_.y()) * scale_};
}

std::optional<Eigen::Vector2d> RpcModel::LocalizeLonLat(const Eigen::Vector2d& col_row, double h,
                                                        const LocalizeOptions& options) const {
  const RpcCoefficients& c = coefficients_;
  // Normalised coordinates beyond this are far outside any RPC's fitted domain.
  constexpr double kMaxNormalised = 10.0;
  Eigen::Vector3d geo(c.long_off, c.lat_off, h);
  Eigen::Matrix<double, 2, 3> jacobian;
  // The tolerance cannot be below what double resolves at the RPC's pixel magnitude.
  const double resolution_px = 8 * std::numeric_limits<double>::epsilon() * std::abs(scale_) *
                               (std::abs(c.samp_off) + std::abs(c.samp_scale) +
                                std::abs(c.line_off) + std::abs(c.line_scale));
  const double tolerance_px = std::max(options.tolerance_px, resolution_px);
  for (int it = 0; it <= options.max_iterations; ++it) {
    const Eigen::Vector2d residual = PixelFromGeo(geo, &jacobian) - col_row;
    if (!residual.allFinite()) return std::nullopt;
    if (residual.norm() <= tolerance_px) return geo.head<2>();
    if (it == options.max_iterations) break;
    const Eigen::Matrix2d j2 = jacobian.leftCols<2>();
    const double det = j2.determinant();
    if (!std::isfinite(det) || det == 0.0) return std::nullopt;
    geo.head<2>() -= j2.inverse() * residual;
    if (std::abs((geo.x() - c.long_off) / c.long_scale) > kMaxNormalised ||
        std::abs((geo.y() - c.lat_off) / c.lat_scale) > kMaxNormalised) {
      return std::nullopt;
    }
  }
  return std::nullopt;
}

RpcModel RpcModel::WithBias(const Eigen::Vector2d& bias_col_row) const {
  RpcModel out = *this;
  out.bias_ = bias_col_row;
  return out;
}

RpcModel RpcModel::Cropped(const Eigen::Vector2d& window_origin_col_row) const {
  // Current pixel = (q - o) * s; the window starts at w in that grid, so the new pixel
  // is (q - o) * s - w = (q - (o + w / s)) * s.
  RpcModel out = *this;
  out.window_origin_ = window_origin_ + window_origin_col_row / scale_;
  return out;
}

RpcModel RpcModel::AtLevel(int level) const {
  SATMESH_CHECK(level >= 0 && level < 31, ErrorCode::kInvalidArgument,
                "pyramid level " + std::to_string(level) + " out of range [0, 30]");
  RpcModel out = *this;
  out.scale_ = scale_ / static_cast<double>(1 << level);
  return out;
}

}  // namespace satmesh
