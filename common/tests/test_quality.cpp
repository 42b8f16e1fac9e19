// Quality measures against values computed by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "pectus/quality.h"

using pectus::Vec3;

namespace {
const double kPi = 3.14159265358979323846;
// eq. 3-23 written the thesis' way, from corner angles and side-length ratios, as an independent check
double betaFromAngles(const std::array<Vec3, 4>& p) {
  double s = 0;
  for (int k = 0; k < 4; ++k) {
    const Vec3 e1 = p[(k + 1) % 4] - p[k], e2 = p[(k + 3) % 4] - p[k];
    const double r = e2.norm() / e1.norm();
    const double theta = std::acos(e1.dot(e2) / (e1.norm() * e2.norm()));
    s += (1 + r * r) / (r * std::sin(theta));
  }
  return 8.0 / s;
}
}  // namespace

TEST(TriangleAlpha, EquilateralIsOne) {
  EXPECT_NEAR(pectus::triangleAlpha(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, std::sqrt(3.0) / 2, 0)), 1.0, 1e-12);
  // orientation and position in space do not matter
  EXPECT_NEAR(pectus::triangleAlpha(Vec3(1, 2, 3), Vec3(1, 2 + std::sqrt(3.0) / 2, 3.5), Vec3(1, 2, 4)), 1.0, 1e-12);
}

TEST(TriangleAlpha, DegenerateIsZero) {
  EXPECT_DOUBLE_EQ(pectus::triangleAlpha(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)), 0.0);
  EXPECT_DOUBLE_EQ(pectus::triangleAlpha(Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 0)), 0.0);
}

TEST(TriangleAlpha, RightIsoscelesByHand) {
  // |AB x AC| = 1, sum of squared sides = 1 + 1 + 2 = 4 -> alpha = 2 sqrt(3) / 4
  EXPECT_NEAR(pectus::triangleAlpha(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)), std::sqrt(3.0) / 2, 1e-12);
}

TEST(TriangleAlpha, SignedFollowsReferenceNormal) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), up(0, 0, 1);
  EXPECT_GT(pectus::triangleAlphaSigned(a, b, c, up), 0.8);
  EXPECT_LT(pectus::triangleAlphaSigned(a, c, b, up), -0.8);
}

TEST(QuadBeta, SquareIsOne) {
  EXPECT_NEAR(pectus::quadBeta(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)), 1.0, 1e-12);
  EXPECT_NEAR(pectus::quadBeta(Vec3(0, 0, 5), Vec3(0, 2, 5), Vec3(0, 2, 7), Vec3(0, 0, 7)), 1.0, 1e-12);
}

TEST(QuadBeta, RectangleByHand) {
  // 2x1 rectangle: every corner r = 2 or 1/2, theta = 90 deg: (1 + 4)/2 = 2.5 each -> beta = 8/10
  EXPECT_NEAR(pectus::quadBeta(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 0), Vec3(0, 1, 0)), 0.8, 1e-12);
}

TEST(QuadBeta, Angle179IsNearlyZero) {
  const double h = std::tan(0.5 * kPi / 180.0);  // interior angle at p3 = 179 degrees
  const std::array<Vec3, 4> p{Vec3(-1, 0, 0), Vec3(0, -1, 0), Vec3(1, 0, 0), Vec3(0, h, 0)};
  const double beta = pectus::quadBeta(p[0], p[1], p[2], p[3]);
  EXPECT_NEAR(beta, betaFromAngles(p), 1e-9);
  EXPECT_LT(beta, 0.07);
  EXPECT_GT(beta, 0.0);
}

TEST(QuadBeta, InvertedIsNotPositive) {
  // reflex corner (non-convex)
  EXPECT_LE(pectus::quadBeta(Vec3(-1, 0, 0), Vec3(0, -1, 0), Vec3(1, 0, 0), Vec3(0, -0.2, 0)), 0.0);
  // bow-tie (self-crossing)
  EXPECT_LE(pectus::quadBeta(Vec3(0, 0, 0), Vec3(1, 1, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)), 0.0);
  // a square turned the other way round a given normal
  EXPECT_LE(pectus::quadBetaWithNormal(Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)), 0.0);
  // collapsed
  EXPECT_LE(pectus::quadBeta(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(3, 0, 0)), 0.0);
}

TEST(QuadBeta, MatchesAngleFormulaOnGeneralConvexQuad) {
  const std::array<Vec3, 4> p{Vec3(0, 0, 0), Vec3(3, 0.4, 0), Vec3(2.5, 2, 0), Vec3(-0.3, 1.5, 0)};
  EXPECT_NEAR(pectus::quadBeta(p[0], p[1], p[2], p[3]), betaFromAngles(p), 1e-12);
}

TEST(QuadBeta, SurfaceQuadFoldedSlightlyStaysNearOne) {
  // unit square with one corner lifted by 0.05: a warped surface quad, measured along its own normal
  const double b = pectus::quadBeta(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0.05), Vec3(0, 1, 0));
  EXPECT_GT(b, 0.99);
  EXPECT_LT(b, 1.0);
}

TEST(Summary, HistogramAndStats) {
  const auto s = pectus::summarizeQuality({0.05, 0.15, 0.95, 1.0, 0.0, 0.55}, 10);
  EXPECT_EQ(s.count, 6u);
  EXPECT_DOUBLE_EQ(s.min, 0.0);
  EXPECT_DOUBLE_EQ(s.max, 1.0);
  EXPECT_NEAR(s.mean, 2.7 / 6, 1e-12);
  EXPECT_EQ(s.invalid, 1u);
  const std::vector<std::size_t> h{2, 1, 0, 0, 0, 1, 0, 0, 0, 2};
  EXPECT_EQ(s.histogram, h);
}
