// Nuss bar planner core on a coarse generated rib cage (linear TET4, seconds): a one-bar row equals the
// single analysis at the same level, two bars need a different force, both bars' loads are in equilibrium
// with the stated shares, volumes grow and the index drops, bar exits derived from the ribs sit where the
// generator's landmarks are, and the bad-input messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>

#include "pectus/nuss/bar_planner.h"
#include "pectus/errors.h"
#include "pectus/fixture/coarse_cage.h"

using namespace pectus;

namespace {

using pectus::fixture::errorOf;

struct Cage {
  const CMeshO& mesh;
  const std::vector<Landmark>& lms;
  nuss::CageSurface surf;
};

const Cage& cage() {
  static const Cage c{fixture::coarseCage().mesh, fixture::coarseCage().lms, nuss::cageFromMesh(fixture::coarseCage().mesh)};
  return c;
}

nuss::PlanOptions quick() {
  nuss::PlanOptions o;
  o.analysis.mesh.order = 1;
  o.analysis.mesh.radiusEdgeRatio = 0;
  o.analysis.nonlinear = false;
  o.analysis.targetElevation = 20.0;
  o.levels = {4};
  o.slice.resolution = 256;
  o.slice.rays = 360;
  o.envelope.nLong = 8;
  o.envelope.mAround = 8;
  o.indexRays = 360;
  return o;
}

std::vector<Landmark> without(std::vector<Landmark> lms, const std::function<bool(int)>& drop) {
  lms.erase(std::remove_if(lms.begin(), lms.end(), [&](const Landmark& l) { return drop(l.code); }), lms.end());
  return lms;
}

}  // namespace

TEST(BarPlanner, ParsesLevels) {
  EXPECT_EQ(nuss::parseLevels("3,4,5"), (std::vector<int>{3, 4, 5}));
  EXPECT_EQ(nuss::parseLevels(" 5; 3 4,4 "), (std::vector<int>{5, 3, 4}));
  EXPECT_EQ(nuss::parseLevels("3-5"), (std::vector<int>{3, 4, 5}));
  EXPECT_NE(errorOf([] { nuss::parseLevels(""); }).find("no level"), std::string::npos);
  EXPECT_NE(errorOf([] { nuss::parseLevels(" , "); }).find("no level"), std::string::npos);
  EXPECT_NE(errorOf([] { nuss::parseLevels("4,x"); }).find("'x' is not a whole number"), std::string::npos);
  EXPECT_NE(errorOf([] { nuss::parseLevels("4.5"); }).find("not a whole number"), std::string::npos);
  EXPECT_NE(errorOf([] { nuss::parseLevels("0,4"); }).find("start at 1"), std::string::npos);
  EXPECT_NE(errorOf([] { nuss::parseLevels("5-3"); }).find("ascending"), std::string::npos);
}

TEST(BarPlanner, BarExitsFromTheRibsMatchTheLandmarks) {
  const auto& c = cage();
  const auto noExits = without(c.lms, [](int code) { return code >= 600 && code < 700; });
  for (int side = 1; side <= 2; ++side)
    for (int s = 4; s <= 5; ++s) {
      const Eigen::Vector3d lm = *findLandmark(c.lms, barExitLandmark(side, s));
      const Eigen::Vector3d derived = nuss::barExit(c.surf, noExits, side, s);
      EXPECT_LT((derived - lm).norm(), 6.0) << "side " << side << " space " << s;
    }
  // exits go down with the space number, every side
  for (int side = 1; side <= 2; ++side)
    EXPECT_GT(nuss::barExit(c.surf, noExits, side, 3).z(), nuss::barExit(c.surf, noExits, side, 6).z() + 20.0);
  EXPECT_NE(errorOf([&] { nuss::barExit(c.surf, noExits, 1, 12); }).find("outside the ribs"), std::string::npos);
}

TEST(BarPlanner, OneBarRowIsTheSingleAnalysisAndTwoBarsDiffer) {
  const auto& c = cage();
  auto o = quick();
  std::vector<std::string> seen;
  o.progress = [&](int, const std::string& w) { seen.push_back(w); };
  const nuss::Plan plan = nuss::planBars(c.surf, c.lms, o);
  ASSERT_EQ(plan.rows.size(), 2u);
  EXPECT_FALSE(seen.empty());
  const auto& one = plan.rows[0];
  const auto& two = plan.rows[1];
  EXPECT_EQ(one.option, "1 bar, space 4");
  EXPECT_EQ(two.option, "2 bars, spaces 4 + 3");
  EXPECT_EQ(two.secondLevel, 3);

  // the one-bar row is the FE filter's analysis at the same level (same mesh, same placement)
  nuss::Options single = o.analysis;
  single.place.intercostalSpace = 4;
  const nuss::Analysis a = nuss::analyze(c.surf, c.lms, single);
  EXPECT_NEAR(one.force, a.force, 1e-6 * a.force);
  EXPECT_NEAR(one.maxStress, a.maxStressBody, 1e-6 * a.maxStressBody);  // away from the tissue junctions too
  EXPECT_EQ(one.maxStressAt, a.maxStressBodyAt.describe());
  EXPECT_EQ(plan.tets, a.mesh.numTets());

  // both reach the target; the second bar changes the required force (by more than 1 %)
  EXPECT_NEAR(one.elevation, 20.0, 0.1);
  EXPECT_NEAR(two.elevation, 20.0, 0.1);
  EXPECT_GT(std::abs(two.force - one.force), 0.01 * one.force);
  // the corrected cage encloses more, measured by both methods, and its index drops
  for (const auto& r : plan.rows) {
    EXPECT_GT(r.sliceGain, 0.0) << r.option;
    EXPECT_GT(r.envelopeGain, 0.0) << r.option;
    EXPECT_NEAR(r.slicePercent, 100.0 * r.sliceGain / plan.sliceBefore, 1e-9);
    EXPECT_LT(r.hallerAfter, plan.hallerBefore) << r.option;
    EXPECT_GT(r.maxStrain, 0.0);
  }
  // the best option (lowest force) is the one kept
  EXPECT_EQ(plan.best, one.force <= two.force ? 0 : 1);
  EXPECT_NEAR(plan.bestAnalysis.force, plan.rows[plan.best].force, 1e-12);

  // the table and the CSV carry every row
  EXPECT_EQ(nuss::planTable(plan).size(), 3u);
  const std::string csv = ::testing::TempDir() + "plan.csv";
  nuss::writePlanCsv(csv, plan);
  std::ifstream in(csv);
  std::string line;
  int lines = 0;
  while (std::getline(in, line)) ++lines;
  EXPECT_EQ(lines, 3);
  EXPECT_NE(errorOf([&] { nuss::writePlanCsv("/nonexistent-dir/plan.csv", plan); }).find("Cannot write"), std::string::npos);
}

TEST(BarPlanner, TwoBarLoadsAreSharedAndInEquilibrium) {
  const auto& c = cage();
  nuss::Options o = quick().analysis;
  o.targetElevation = 0;
  o.force = 100;
  o.place.secondSpace = 2;  // ribs 2, 3: no rib shared with the first bar's 4, 5, so each patch carries one bar's Fsr
  o.place.secondShare = 0.3;
  const nuss::Analysis a = nuss::analyze(c.surf, c.lms, o);
  ASSERT_EQ(a.supportNodes.size(), 8u);
  EXPECT_EQ(a.supportNames[4], "right rib 2");
  EXPECT_EQ(a.supportNames[7], "left rib 3");
  ASSERT_FALSE(a.secondSternumNodes.empty());
  const fe::Problem p = nuss::problemAt(a, o, 100.0);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& f : p.force) sum += f;
  EXPECT_LT(sum.norm(), 1e-9);
  auto fy = [&](const std::vector<int>& nodes) {
    double s = 0;
    for (int n : nodes) s += p.force[n].y();
    return s;
  };
  EXPECT_NEAR(fy(a.sternumNodes), 70.0, 1e-9);
  EXPECT_NEAR(fy(a.secondSternumNodes), 30.0, 1e-9);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(fy(a.supportNodes[k]), -17.5, 1e-9);
  for (int k = 4; k < 8; ++k) EXPECT_NEAR(fy(a.supportNodes[k]), -7.5, 1e-9);
  // the second bar's patch sits above the first one's, on the sternum
  double z1 = 0, z2 = 0;
  for (int n : a.sternumNodes) z1 += a.mesh.nodes[n].z() / a.sternumNodes.size();
  for (int n : a.secondSternumNodes) z2 += a.mesh.nodes[n].z() / a.secondSternumNodes.size();
  EXPECT_GT(z2, z1 + 5.0);
}

TEST(BarPlanner, BadInputIsRefusedBeforeAnySolve) {
  const auto& c = cage();
  auto o = quick();
  int solves = 0;
  o.progress = [&](int, const std::string& w) { solves += w.find("Calibrating") != std::string::npos; };
  auto fails = [&](nuss::PlanOptions x, const std::vector<Landmark>& lms, const std::string& what) {
    const std::string e = errorOf([&] { nuss::planBars(c.surf, lms, x); });
    EXPECT_NE(e.find(what), std::string::npos) << "expected '" << what << "', got '" << e << "'";
  };
  auto empty = o;
  empty.levels.clear();
  fails(empty, c.lms, "No bar level");
  auto outside = o;
  outside.levels = {4, 12};  // ribs 12 and 13: the cage has 12 rib pairs
  fails(outside, c.lms, "outside the ribs");
  auto offsetZero = o;
  offsetZero.secondOffset = 0;
  fails(offsetZero, c.lms, "offset");
  auto below1 = o;
  below1.levels = {1};
  fails(below1, c.lms, "intercostal space 0");
  auto share = o;
  share.secondShare = 1.5;
  fails(share, c.lms, "share");
  auto noTarget = o;
  noTarget.analysis.targetElevation = 0;
  fails(noTarget, c.lms, "target elevation");
  auto none = o;
  none.oneBar = none.twoBars = false;
  fails(none, c.lms, "Neither");
  fails(o, without(c.lms, [](int code) { return code == kDiaphragmDome; }), "Landmark 700");
  EXPECT_EQ(solves, 0);
}
