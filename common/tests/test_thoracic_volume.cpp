// Unit tests of the thoracic volume cores on analytic cages with known volumes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "analytic_cages.h"
#include "pectus/errors.h"
#include "pectus/vol/thoracic_volume.h"

using namespace pectus::vol;
using namespace pectus::vol::testing;

namespace {
double rel(double v, double exact) { return std::abs(v - exact) / exact; }
}  // namespace

TEST(ThoracicVolumeDivergence, CubeAndEllipsoid) {
  // unit cube, outward triangles
  Soup cube;
  for (int i = 0; i < 8; ++i) cube.V.push_back({double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
  const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (auto& f : q) cube.F.push_back({f[0], f[1], f[2]}), cube.F.push_back({f[0], f[2], f[3]});
  EXPECT_NEAR(divergenceVolume(cube), 1.0, 1e-12);
  const auto e = closedEllipsoid(120, 90, 150, 256, 128);
  EXPECT_LT(rel(divergenceVolume(e), 4.0 / 3.0 * kPi * 120 * 90 * 150), 1e-3);
}

TEST(ThoracicVolumeSlice, BandedEllipticCylinderWithin0p2Percent) {
  const double a = 130, b = 90;
  const auto cage = bandedCylinder(a, b, 8, 0, 240, 720, 240);
  SliceParams p;  // thesis defaults: 2.6 mm, 512 x 512
  const auto r = sliceVolume(cage, {20, 220}, p);
  const double exact = kPi * a * b * 200;
  EXPECT_EQ(r.emptySlices, 0);
  EXPECT_LT(r.minCoverage, 0.95) << "the test cage must have gaps to close";
  EXPECT_LT(rel(r.volume, exact), 2e-3) << r.volume << " vs " << exact;
  EXPECT_LT(rel(r.polygonVolume, exact), 2e-3);
}

TEST(ThoracicVolumeSlice, BandedEllipsoidWithin0p2Percent) {
  const double a = 120, b = 85, c = 150;
  const auto cage = bandedEllipsoid(a, b, c, 8, 130, 720, 520);
  const auto r = sliceVolume(cage, {-110, 110}, SliceParams{});
  const double exact = ellipsoidSegmentVolume(a, b, c, -110, 110);
  EXPECT_LT(rel(r.volume, exact), 2e-3) << r.volume << " vs " << exact << " min coverage " << r.minCoverage;
}

namespace {
/// horizontal rib bands (no slope, no sternum or spine strip): bands [25 k, 25 k + 15) mm, gaps of 10 mm,
/// so 40 % of the planes cut nothing
RibMask horizontalBands() {
  RibMask m;
  m.pitch = 25, m.ribFraction = 0.6, m.tilt = 0, m.stripHalfAngle = 0;
  return m;
}
/// the volume the slices with a cut of their own give (the bridged slices counted as zero)
double unbridgedVolume(const SliceResult& r) {
  double v = 0;
  for (int k = 0; k < r.slices; ++k)
    if (!r.bridged[k]) v += r.area[k] * r.spacingUsed;
  return v;
}
}  // namespace

TEST(ThoracicVolumeSlice, HorizontalBandsWithGapsAreBridged) {
  const double a = 130, b = 90;
  const auto cage = bandedCylinder(a, b, 8, 0, 240, 720, 240, horizontalBands());
  const Range range{5, 210};  // both ends inside a band
  const auto r = sliceVolume(cage, range, SliceParams{});
  const double exact = kPi * a * b * (range.zHi - range.zLo);
  std::printf("horizontal bands, cylinder: %d slices, %d bridged; error %.4f %% (unbridged %.2f %%)\n", r.slices,
              r.bridgedSlices, 100 * rel(r.volume, exact), 100 * rel(unbridgedVolume(r), exact));
  EXPECT_GT(r.bridgedSlices, r.slices / 4) << "the test cage must have planes that cut nothing";
  EXPECT_EQ(r.bridgedSlices, r.emptySlices);
  EXPECT_EQ(r.endEmptySlices, 0);
  EXPECT_LT(unbridgedVolume(r), 0.7 * exact) << "without bridging the gaps count as zero";
  EXPECT_LT(rel(r.volume, exact), 5e-3) << r.volume << " vs " << exact;
  EXPECT_LT(rel(r.polygonVolume, exact), 5e-3) << r.polygonVolume << " vs " << exact;
}

TEST(ThoracicVolumeSlice, HorizontalBandsOnATaperingCageAreBridged) {
  // the section changes between the bands: the bridged regions follow the wall between the cuts
  const double a = 120, b = 85, c = 150;
  const auto cage = bandedEllipsoid(a, b, c, 8, 130, 720, 520, horizontalBands());
  const Range range{-120, 110};  // both ends inside a band
  const auto r = sliceVolume(cage, range, SliceParams{});
  const double exact = ellipsoidSegmentVolume(a, b, c, range.zLo, range.zHi);
  std::printf("horizontal bands, ellipsoid: %d slices, %d bridged; error %.4f %% (unbridged %.2f %%)\n", r.slices,
              r.bridgedSlices, 100 * rel(r.volume, exact), 100 * rel(unbridgedVolume(r), exact));
  EXPECT_GT(r.bridgedSlices, r.slices / 4);
  EXPECT_EQ(r.endEmptySlices, 0);
  EXPECT_LT(rel(r.volume, exact), 5e-3) << r.volume << " vs " << exact;
}

TEST(ThoracicVolumeSlice, EmptySlicesAtTheEndsAreNotBridged) {
  // the range starts and ends in a gap: the planes below the first band and above the last one have
  // nothing to interpolate from and count as zero; those between the bands are bridged
  const auto cage = bandedCylinder(130, 90, 8, 0, 240, 720, 240, horizontalBands());
  const auto r = sliceVolume(cage, {18, 222}, SliceParams{});
  ASSERT_GT(r.endEmptySlices, 1);
  EXPECT_GT(r.bridgedSlices, 0);
  EXPECT_EQ(r.emptySlices, r.bridgedSlices + r.endEmptySlices);
  int lowEnd = 0, highEnd = 0;
  while (r.area[lowEnd] == 0) ++lowEnd;
  while (r.area[r.slices - 1 - highEnd] == 0) ++highEnd;
  EXPECT_GT(lowEnd, 0);
  EXPECT_GT(highEnd, 0);
  EXPECT_EQ(lowEnd + highEnd, r.endEmptySlices);
  for (int k = 0; k < r.slices; ++k) {
    EXPECT_EQ(r.area[k] > 0, k >= lowEnd && k < r.slices - highEnd) << "slice " << k << " z = " << r.z[k];
    EXPECT_EQ(bool(r.bridged[k]), r.area[k] > 0 && r.z[k] >= 25 && std::fmod(r.z[k], 25.0) >= 15) << "slice " << k;
  }
}

TEST(ThoracicVolumeSlice, GapRuleBeatsChords) {
  // the Hermite gap rule must be closer to the ellipse than the chord polygon through the hits
  const double a = 130, b = 90;
  const auto cage = bandedCylinder(a, b, 8, 0, 240, 720, 240);
  auto cuts = cutPlanes(cage, {101.3});
  const auto R = regionFromSegments(101.3, cuts[0], 720);
  ASSERT_FALSE(R.empty());
  ASSERT_LT(R.coverage(), 0.9);
  std::vector<Eigen::Vector2d> chord;
  for (std::size_t k = 0; k < R.hit.size(); ++k)
    if (R.hit[k]) chord.push_back(R.polygon[k]);
  SliceRegion C;
  C.polygon = chord;
  const double exact = kPi * a * b;
  EXPECT_LT(rel(R.polygonArea(), exact), rel(C.polygonArea(), exact));
}

// hits in a narrow arc only (a coarse probe of a deformed cage: 3 of 64 rays hit): the closure of the gap of
// more than half a turn stays inside the farthest hit; the chord's line, nearly parallel to some of the
// gap's rays, would give radii of kilometres and a raster box that swallows every other slice (as in the
// envelope filter's coarse probe of an FE result)
TEST(ThoracicVolumeSlice, GapOfMoreThanHalfATurnStaysInside) {
  std::vector<Seg2> arc;
  const double r = 100;
  for (double deg : {0.0, 20.0, 40.0, 60.0, 80.0}) {
    const double a0 = (deg - 3) * kPi / 180, a1 = (deg + 3) * kPi / 180;
    arc.push_back({Eigen::Vector2d(r * std::cos(a0), r * std::sin(a0)), Eigen::Vector2d(r * std::cos(a1), r * std::sin(a1))});
  }
  const auto R = regionFromSegments(0.0, arc, 64, Eigen::Vector2d(0, 0));
  ASSERT_GE(R.hits, 3);
  ASSERT_LT(R.coverage(), 0.2);
  double farthest = 0;
  for (const auto& q : R.polygon) farthest = std::max(farthest, q.norm());
  EXPECT_LE(farthest, r * (1 + 1e-9));
  EXPECT_GT(R.polygonArea(), 0);
  EXPECT_LE(R.polygonArea(), kPi * r * r);
}

TEST(ThoracicVolumeEnvelope, ClosedEllipsoidWithin1Percent) {
  const double a = 120, b = 90, c = 150;
  const auto e = closedEllipsoid(a, b, c, 256, 128);
  EnvelopeParams p;
  const auto r = fergusonEnvelope(e, {-90, 90}, p);
  const double exact = ellipsoidSegmentVolume(a, b, c, -90, 90);
  EXPECT_LT(rel(r.volume, exact), 1e-2) << r.volume << " vs " << exact;
  EXPECT_GE(r.volume, exact * (1 - 2e-3)) << "an envelope lies outside the cage";
  EXPECT_EQ(r.singular, 0);
  // the tessellated envelope is closed and its divergence volume converges to the parametric one
  const auto mesh = r.env.tessellate(12);
  EXPECT_LT(rel(divergenceVolume(mesh), r.volume), 2e-3);
}

TEST(ThoracicVolumeEnvelope, BandedCylinderWithin1Percent) {
  const double a = 130, b = 90, t = 8;
  const auto cage = bandedCylinder(a, b, t, 0, 240, 720, 240);
  const auto r = fergusonEnvelope(cage, {20, 220}, EnvelopeParams{});
  const double exact = kPi * (a + t) * (b + t) * 200;
  EXPECT_LT(rel(r.volume, exact), 1e-2) << r.volume << " vs " << exact;
  EXPECT_GT(r.touching, 0);
}

TEST(ThoracicVolumeEnvelope, RaysHitTheSurfaceNewton) {
  const auto e = closedEllipsoid(100, 100, 100, 128, 64);
  const auto r = fergusonEnvelope(e, {-50, 50}, EnvelopeParams{});
  // every ray from the axis meets the surface; the point found lies on the ray's angle
  for (double ang = 0.05; ang < 6.28; ang += 0.37) {
    int its = 0;
    const double rho = r.env.rayRadius(ang, 13.0, &its);
    EXPECT_GT(rho, 0.8 * std::sqrt(100 * 100 - 13.0 * 13.0));
    EXPECT_LT(its, 30);
  }
}

TEST(ThoracicVolumeEnvelope, SingularKeyPointsTiedAcrossAnOpening) {
  // a cylinder with a large anterior opening (like the abdominal hole): the key points there are
  // singular and tied to their neighbours, so the envelope does not fall into the opening
  const double a = 130, b = 90;
  Soup cage;
  addSheet(cage, 720, 240, 0, 240,
           [&](double th, double z) { return Eigen::Vector3d(a * std::cos(th), b * std::sin(th), z); },
           [](double th, double z) { return !(z < 110 && std::abs(std::remainder(th - kPi / 2, 2 * kPi)) < 0.9); });
  const auto r = fergusonEnvelope(cage, {20, 220}, EnvelopeParams{});
  EXPECT_GT(r.singular, 0);
  // tied key points take their neighbours' radius: the envelope spans the opening (flat or convex,
  // never falling in), so it holds at least the closed cylinder and a bounded bulge more
  const double exact = kPi * a * b * 200;
  EXPECT_GT(r.volume, exact * 0.99) << r.volume << " vs " << exact;
  EXPECT_LT(r.volume, exact * 1.15) << r.volume << " vs " << exact;
  EXPECT_GE(r.env.rayRadius(kPi / 2, 60.0), b - 0.5);
}

TEST(ThoracicVolumeBadInput, NoGeometryInRange) {
  const auto cage = bandedCylinder(130, 90, 8, 0, 240, 180, 60);
  EXPECT_THROW(sliceVolume(cage, {300, 400}, SliceParams{}), pectus::InputError);
  EXPECT_THROW(fergusonEnvelope(cage, {300, 400}, EnvelopeParams{}), pectus::InputError);
}

TEST(ThoracicVolumeBadInput, DegenerateAxisAndRange) {
  const auto cage = bandedCylinder(130, 90, 8, 0, 240, 180, 60);
  EXPECT_THROW(sliceVolume(cage, {100, 100}, SliceParams{}), pectus::InputError);
  EXPECT_THROW(fergusonEnvelope(cage, {120, 80}, EnvelopeParams{}), pectus::InputError);
  Soup line;  // a vertical sliver: no extent across the axis
  line.V = {{0, 0, 0}, {0, 0, 100}, {0, 0, 50}};
  line.F = {{0, 1, 2}};
  EXPECT_THROW(fergusonEnvelope(line, {10, 90}, EnvelopeParams{}), pectus::InputError);
}

// the cores check the lower ends of the declared spacing and minimum step (thoracic_volume.h)
TEST(ThoracicVolumeBadInput, SpacingAndMinimumStepBelowTheirRanges) {
  const auto cage = bandedCylinder(130, 90, 8, 0, 240, 180, 60);
  SliceParams slice;
  slice.spacing = kSpacingRange.lo / 2;
  EXPECT_THROW(sliceVolume(cage, {60, 180}, slice), pectus::InputError);
  slice.spacing = 10 * kSpacingRange.hi;  // one slice, as the envelope filter's coverage probe may ask
  EXPECT_NO_THROW(sliceVolume(cage, {60, 180}, slice));
  EnvelopeParams env;
  env.minStep = kMinStepRange.lo / 2;
  EXPECT_THROW(fergusonEnvelope(cage, {60, 180}, env), pectus::InputError);
}

TEST(ThoracicVolumeBadInput, PairMismatch) {
  const auto a = bandedCylinder(130, 90, 8, 0, 240, 180, 60);
  const auto b = bandedCylinder(130, 90, 8, 0, 240, 180, 61);
  EXPECT_THROW(requireComparablePair(a, b, "before", "after"), pectus::InputError);
  auto c = a;  // same mesh in metres: another frame
  for (auto& v : c.V) v *= 0.001;
  EXPECT_THROW(requireComparablePair(a, c, "before", "after"), pectus::InputError);
  auto d = a;  // a local correction: accepted
  for (auto& v : d.V)
    if (v.y() > 60) v.y() += 10;
  EXPECT_NO_THROW(requireComparablePair(a, d, "before", "after"));
}

TEST(ThoracicVolumeChange, DeformedCopyGainsVolume) {
  // the anterior wall pushed forward: both methods see a positive change
  const auto before = bandedCylinder(130, 90, 8, 0, 240, 720, 240);
  auto after = before;
  for (auto& v : after.V)
    if (v.y() > 0) v.y() *= 1.1;
  const auto s0 = sliceVolume(before, {20, 220}, SliceParams{}), s1 = sliceVolume(after, {20, 220}, SliceParams{});
  EXPECT_NEAR(s1.volume / s0.volume, 1.05, 2e-3);
  const auto e0 = fergusonEnvelope(before, {20, 220}, EnvelopeParams{});
  const auto e1 = fergusonEnvelope(after, {20, 220}, EnvelopeParams{});
  EXPECT_GT(e1.volume, e0.volume);
}

TEST(PectusIndexTest, DentedPrism) {
  const double a = 130, b = 90, D = 40, w = 45;
  auto yOf = [&](double th) {
    const double x = a * std::cos(th), y = b * std::sin(th);
    return y > 0 ? y - D * std::exp(-x * x / (w * w)) : y;
  };
  Soup cage;
  addSheet(cage, 720, 60, 0, 120, [&](double th, double z) { return Eigen::Vector3d(a * std::cos(th), yOf(th), z); }, {});
  double ymax = -1e9;
  for (int k = 0; k < 100000; ++k) ymax = std::max(ymax, yOf(2 * kPi * k / 100000));
  IndexInputs in;
  in.level = 60.3;
  in.midlineX = 0.0;
  const auto pi = pectusIndex(cage, in);
  EXPECT_NEAR(pi.transverse, 2 * a, 0.5);
  EXPECT_NEAR(pi.apMin, 2 * b - D, 0.5);
  EXPECT_NEAR(pi.haller, 2 * a / (2 * b - D), 0.01);
  EXPECT_NEAR(pi.correction, 100 * (ymax + b - (2 * b - D)) / (ymax + b), 0.3);
  in.spineY = -b;
  EXPECT_NEAR(pectusIndex(cage, in).apMin, 2 * b - D, 0.5);
  // automatic level on a prism: any slice, same index
  IndexInputs au;
  au.searchRange = {10, 110};
  EXPECT_NEAR(pectusIndex(cage, au).haller, 2 * a / (2 * b - D), 0.02);
}

TEST(ThoracicVolumeSlice, RasterResolutionIsUsed) {
  // the raster converges to the polygon areas as the resolution grows
  const auto cage = bandedCylinder(130, 90, 8, 0, 240, 720, 240);
  SliceParams coarse;
  coarse.resolution = 24;
  const auto c = sliceVolume(cage, {20, 220}, coarse), f = sliceVolume(cage, {20, 220}, SliceParams{});
  EXPECT_NEAR(c.pixel / f.pixel, 512.0 / 24.0, 1e-9);
  EXPECT_GT(std::abs(c.volume - c.polygonVolume), std::abs(f.volume - f.polygonVolume));
  EXPECT_LT(std::abs(f.volume - f.polygonVolume) / f.polygonVolume, 5e-4);
}

// an open, wavy sheet whose one slice region collapses to a point (every ray stops at the seed): the slices'
// common box would have no extent and the pixel size would be 0 / resolution (UBSan: NaN cast to int). A
// region without area counts as empty, and a range with only such regions is refused.
TEST(ThoracicVolumeSlice, RegionsWithoutAreaAreRefused) {
  Soup s;
  s.V = {{-41.4578, -4.26848, 1.37812},  {17.7676, -4.26848, -0.121875}, {76.9887, -4.26848, 5.87741},
         {-41.4578, -1.75761, -0.847018}, {-14.0338, -2.87322, -2.2232},  {44.939, -3.00651, 0.0107159},
         {-41.6801, 0.0573667, 1.54273},  {0.848867, -0.322695, -1.98586}, {46.4187, -0.117251, 0.330441},
         {-51.9267, 2.46185, 0.82637},    {-11.2283, 3.03103, -2.04545},  {51.4089, 2.60888, 0.942296},
         {-70.3036, 4.82974, 1.68156},    {-4.23783, 4.88865, -3.62321},  {72.1574, 5.14288, 0.455202}};
  s.F = {{0, 1, 4},   {0, 4, 3},   {1, 2, 5},   {1, 5, 4},   {3, 4, 7},   {3, 7, 6},
         {4, 5, 8},   {4, 8, 7},   {6, 7, 10},  {6, 10, 9},  {7, 8, 11},  {7, 11, 10},
         {9, 10, 13}, {9, 13, 12}, {10, 11, 14}, {10, 14, 13}, {0, 3, 13}};
  SliceParams p;
  p.spacing = 20;  // one plane, at the middle of the range
  p.rays = 18;
  p.resolution = 16;
  const Range range{-2.35515, 7.77753};
  try {
    const SliceResult r = sliceVolume(s, range, p);
    ADD_FAILURE() << "no error; pixel " << r.pixel << ", volume " << r.volume;
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no geometry in the measured range"), std::string::npos) << e.what();
  }
}
