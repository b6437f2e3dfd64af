#include "core/rpc/rpc_model.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "core/common/error.h"
#include "tests/core/rpc/test_cameras.h"

namespace satmesh {
namespace {

// Realistic models: RPCs fitted to pushbroom cameras at several off-nadir angles.
const std::vector<RpcModel>& Models() {
  static const std::vector<RpcModel> models = [] {
    std::vector<RpcModel> out;
    const double zeniths[] = {5, 20, 35}, azimuths[] = {100, 10, 235}, gsds[] = {0.3, 0.4, 0.5};
    for (int i = 0; i < 3; ++i) {
      test::PushbroomParams p;
      p.zenith_deg = zeniths[i], p.azimuth_deg = azimuths[i], p.gsd_m = gsds[i];
      out.push_back(test::FitPushbroom(p).model);
    }
    return out;
  }();
  return models;
}

// Points inside the model's normalised domain (|L|, |P|, |H| <= 0.9).
std::vector<Eigen::Vector3d> DomainPoints(const RpcModel& model, int n, unsigned seed) {
  const RpcCoefficients& c = model.coefficients();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.9, 0.9);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < n; ++i) {
    out.emplace_back(c.long_off + u(rng) * c.long_scale, c.lat_off + u(rng) * c.lat_scale,
                     c.height_off + u(rng) * c.height_scale);
  }
  return out;
}

std::string ErrorMessage(const std::map<std::string, std::string>& md) {
  try {
    RpcModel::FromKeyValues(md);
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidInput);
    return e.what();
  }
  ADD_FAILURE() << "no error thrown";
  return "";
}

TEST(RpcModel, KeyValuesRoundTripExactly) {
  const RpcModel& m = Models()[1];
  const RpcModel back = RpcModel::FromKeyValues(m.ToKeyValues());
  EXPECT_EQ(back.coefficients().samp_num, m.coefficients().samp_num);
  EXPECT_EQ(back.coefficients().line_den, m.coefficients().line_den);
  EXPECT_EQ(back.coefficients().lat_off, m.coefficients().lat_off);
}

TEST(RpcModel, MissingKeyIsNamed) {
  for (const auto& [key, value] : Models()[0].ToKeyValues()) {
    auto md = Models()[0].ToKeyValues();
    md.erase(key);
    const std::string message = ErrorMessage(md);
    EXPECT_NE(message.find(key), std::string::npos) << message;
    EXPECT_NE(message.find("missing"), std::string::npos) << message;
  }
}

TEST(RpcModel, UnparsableValueIsNamed) {
  auto md = Models()[0].ToKeyValues();
  md["LINE_OFF"] = "abc";
  EXPECT_NE(ErrorMessage(md).find("LINE_OFF: cannot parse"), std::string::npos);
  md = Models()[0].ToKeyValues();
  md["SAMP_NUM_COEFF"] = "1 2 3";
  EXPECT_NE(ErrorMessage(md).find("SAMP_NUM_COEFF: expected 20"), std::string::npos);
  md["SAMP_NUM_COEFF"] = "1 2 3 4 5 6 7 8 9 1x 11 12 13 14 15 16 17 18 19 20";
  EXPECT_NE(ErrorMessage(md).find("SAMP_NUM_COEFF[9]: cannot parse"), std::string::npos);
}

TEST(RpcModel, NonFiniteValueIsNamed) {
  auto md = Models()[0].ToKeyValues();
  md["LAT_OFF"] = "nan";
  EXPECT_NE(ErrorMessage(md).find("LAT_OFF"), std::string::npos);
  md = Models()[0].ToKeyValues();
  md["HEIGHT_OFF"] = "inf";
  EXPECT_NE(ErrorMessage(md).find("HEIGHT_OFF: value 'inf' is not finite"), std::string::npos);
  RpcCoefficients c = Models()[0].coefficients();
  c.line_num[4] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(RpcModel::FromCoefficients(c), Error);
}

TEST(RpcModel, ZeroScaleIsNamed) {
  const std::vector<std::string> keys = {"LINE_SCALE", "SAMP_SCALE", "LAT_SCALE", "LONG_SCALE",
                                         "HEIGHT_SCALE"};
  for (const std::string& key : keys) {
    auto md = Models()[0].ToKeyValues();
    md[key] = std::string(1, '0');  // (a literal trips GCC 12 -Wrestrict)
    const std::string message = ErrorMessage(md);
    EXPECT_NE(message.find(key), std::string::npos) << message;
    EXPECT_NE(message.find("is zero"), std::string::npos) << message;
  }
}

TEST(RpcModel, ZeroDenominatorConstantIsNamed) {
  auto md = Models()[0].ToKeyValues();
  std::string den = md["LINE_DEN_COEFF"];
  den.replace(0, den.find(' '), "0");
  md["LINE_DEN_COEFF"] = den;
  EXPECT_NE(ErrorMessage(md).find("LINE_DEN_COEFF[0]"), std::string::npos);
}

TEST(RpcModel, AcceptsUnitSuffixAsInRpcTxt) {
  auto md = Models()[0].ToKeyValues();
  md["LINE_OFF"] = "+001000.50 pixels";
  EXPECT_DOUBLE_EQ(RpcModel::FromKeyValues(md).coefficients().line_off, 1000.5);
}

TEST(RpcModel, JacobianMatchesCentralDifferences) {
  for (const RpcModel& base : Models()) {
    const RpcModel derived = base.WithBias({1.5, -2}).Cropped({300, 200}).AtLevel(2);
    for (const RpcModel& m : {base, derived}) {
      const RpcCoefficients& c = m.coefficients();
      // A step of 1e-3 normalised units: truncation ~1e-8 relative, round-off ~1e-11.
      const Eigen::Vector3d step(1e-3 * c.long_scale, 1e-3 * c.lat_scale, 1e-3 * c.height_scale);
      for (const Eigen::Vector3d& g : DomainPoints(m, 50, 7)) {
        Eigen::Matrix<double, 2, 3> j;
        const Eigen::Vector2d px = m.PixelFromGeo(g, &j);
        EXPECT_EQ(px, m.PixelFromGeo(g));
        for (int k = 0; k < 3; ++k) {
          Eigen::Vector3d d = Eigen::Vector3d::Zero();
          d(k) = step(k);
          const Eigen::Vector2d fd = (m.PixelFromGeo(g + d) - m.PixelFromGeo(g - d)) / (2 * step(k));
          EXPECT_LT((fd - j.col(k)).norm(), 1e-6 * j.col(k).norm()) << "column " << k;
        }
      }
    }
  }
}

TEST(RpcModel, LocalizeProjectRoundTrip) {
  for (const RpcModel& m : Models()) {
    for (const Eigen::Vector3d& g : DomainPoints(m, 200, 11)) {
      const Eigen::Vector2d px = m.PixelFromGeo(g);
      const auto lon_lat = m.LocalizeLonLat(px, g.z());
      ASSERT_TRUE(lon_lat.has_value());
      EXPECT_LT((m.PixelFromGeo({lon_lat->x(), lon_lat->y(), g.z()}) - px).norm(), 1e-6);
      EXPECT_LT((*lon_lat - g.head<2>()).norm(), 1e-10);  // 1e-10 deg ~ 10 um
    }
  }
}

TEST(RpcModel, LocalizeFailsFarOutside) {
  const RpcModel& m = Models()[0];
  EXPECT_FALSE(m.LocalizeLonLat({1e9, -1e9}, 0).has_value());
  LocalizeOptions one_step;
  one_step.max_iterations = 1;
  EXPECT_FALSE(m.LocalizeLonLat({1900, 1900}, 50, one_step).has_value());
}

TEST(RpcModel, DerivedModelsAreConsistent) {
  const RpcModel& base = Models()[2];
  const Eigen::Vector2d bias(0.75, -1.25), origin(300, 120);
  const RpcModel biased = base.WithBias(bias);
  const RpcModel cropped = base.Cropped(origin);
  const RpcModel level2 = base.AtLevel(2);
  const RpcModel level2_cropped = level2.Cropped({50, 25});
  EXPECT_EQ(biased.WithBias({0, 0}).bias(), Eigen::Vector2d(0, 0));
  EXPECT_DOUBLE_EQ(level2.pixel_scale(), 0.25);
  for (const Eigen::Vector3d& g : DomainPoints(base, 50, 3)) {
    Eigen::Matrix<double, 2, 3> j_base, j;
    const Eigen::Vector2d px = base.PixelFromGeo(g, &j_base);
    EXPECT_LT((biased.PixelFromGeo(g, &j) - (px + bias)).norm(), 1e-9);
    EXPECT_LT((j - j_base).norm(), 1e-9 * j_base.norm());
    EXPECT_LT((cropped.PixelFromGeo(g) - (px - origin)).norm(), 1e-9);
    EXPECT_LT((level2.PixelFromGeo(g, &j) - px / 4).norm(), 1e-9);
    EXPECT_LT((j - j_base / 4).norm(), 1e-9 * j_base.norm());
    EXPECT_LT((level2_cropped.PixelFromGeo(g) - (px / 4 - Eigen::Vector2d(50, 25))).norm(), 1e-9);
    EXPECT_LT((base.Cropped(origin).Cropped({10, 20}).PixelFromGeo(g) - (px - origin -
                                                                          Eigen::Vector2d(10, 20))).norm(), 1e-9);
    // Localising in a derived model recovers the same ground point.
    const auto ll = level2_cropped.LocalizeLonLat(level2_cropped.PixelFromGeo(g), g.z());
    ASSERT_TRUE(ll.has_value());
    EXPECT_LT((*ll - g.head<2>()).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace satmesh
