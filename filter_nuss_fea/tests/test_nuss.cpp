// Nuss FE analysis core on a coarse generated rib cage: loads in equilibrium (Fe = 2Fs = 4Fsr), joints fixed,
// linear scaling, calibration to a target, nonlinear close to linear at small force, result locations,
// and the bad-input messages (missing labels/landmarks, a part without a joint, unreachable target).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "pectus/nuss/nuss_analysis.h"
#include "pectus/nuss/nuss_output.h"
#include "pectus/nuss/tissue_join.h"
#include "pectus/errors.h"
#include "pectus/labels.h"
#include "pectus/fixture/coarse_cage.h"
#include "pectus/ribcage/ribcage.h"

using namespace pectus;

namespace {

using pectus::fixture::errorOf;
pectus::fixture::CoarseCage& cage() { return pectus::fixture::coarseCage(); }

nuss::Options coarse() {
  nuss::Options o;
  o.mesh.order = 1;
  o.mesh.radiusEdgeRatio = 0;  // boundary-constrained Delaunay only: fast
  o.nonlinear = false;
  o.force = 10;
  return o;
}

}  // namespace

TEST(NussAnalysis, LinearModelLoadsSupportsCalibrationAndBadInput) {
  const auto surf = nuss::cageFromMesh(cage().mesh);
  ASSERT_GT(surf.surface.F.size(), 3000u);
  const auto& lms = cage().lms;

  auto o = coarse();
  const nuss::Analysis a = nuss::analyze(surf, lms, o);
  // every joint landmark holds nodes, four support patches, Fe on the sternum
  EXPECT_GE(a.fixedNodes.size(), 24u * 3);
  ASSERT_EQ(a.supportNodes.size(), 4u);
  for (const auto& s : a.supportNodes) EXPECT_GE(s.size(), 1u);
  EXPECT_EQ(a.supportNames[0], "right rib 4");
  EXPECT_EQ(a.supportNames[3], "left rib 5");
  // loads: Fe along +y on the sternum, the four Fsr = Fe/4 opposite: self-equilibrated
  const fe::Problem p = nuss::problemAt(a, o, 100.0);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), up = Eigen::Vector3d::Zero();
  for (size_t n = 0; n < p.force.size(); ++n) sum += p.force[n];
  for (int n : a.sternumNodes) up += p.force[n];
  EXPECT_LT(sum.norm(), 1e-9);
  EXPECT_NEAR(up.y(), 100.0, 1e-9);
  for (const auto& s : a.supportNodes) {
    double fy = 0;
    for (int n : s) fy += p.force[n].y();
    EXPECT_NEAR(fy, -25.0, 1e-9);
  }
  // joints do not move; the sternum end rises; linear: elevation = compliance * force
  for (int n : a.fixedNodes) EXPECT_EQ(a.result.displacement(n).norm(), 0.0);
  EXPECT_GT(a.elevation, 0.0);
  EXPECT_NEAR(a.elevation, a.linearCompliance * 10.0, 1e-6 * a.elevation);
  ASSERT_GE(a.curve.size(), 2u);
  EXPECT_NEAR(a.curve.back().first, 10.0, 1e-9);
  // the largest strains are in the cartilage (E 940x lower than bone), as the thesis reports
  EXPECT_GT(a.maxStrainCartilage, 10 * a.maxStrainBone);
  EXPECT_EQ(a.maxStrainAt.tissue, int(Tissue::Cartilage));
  EXPECT_GT(a.maxStress, 0.0);
  EXPECT_LE(a.maxStress, a.maxStressAll);
  // away from the tissue junctions too: no node of the peak's tet is shared with a tet of another tissue
  EXPECT_GT(a.maxStressBody, 0.0);
  EXPECT_LE(a.maxStressBody, a.maxStress);
  ASSERT_GE(a.maxStressBodyAt.tet, 0);
  std::vector<std::vector<int>> tissuesOf(a.mesh.nodes.size());
  for (int t = 0; t < a.mesh.numTets(); ++t)
    for (int k = 0; k < a.mesh.nodesPerTet(); ++k) tissuesOf[a.mesh.tets[t][k]].push_back(a.mesh.tissue[t]);
  for (int k = 0; k < a.mesh.nodesPerTet(); ++k) {
    const auto& ts = tissuesOf[a.mesh.tets[a.maxStressBodyAt.tet][k]];
    EXPECT_TRUE(std::all_of(ts.begin(), ts.end(), [&](int x) { return x == ts.front(); }));
  }
  std::printf("max stress %.2f MPa at %s; away from the junctions %.2f MPa at %s\n", a.maxStress,
              a.maxStressAt.describe().c_str(), a.maxStressBody, a.maxStressBodyAt.describe().c_str());
  // the strain path along the right 5th rib starts at the sternum and reaches bone
  const auto path = nuss::strainAlongRib(a, 1, 5);
  ASSERT_GE(path.size(), 10u);
  bool cart = false, bone = false;
  for (const auto& s : path) cart |= s.tissue == int(Tissue::Cartilage), bone |= s.tissue == int(Tissue::Bone);
  EXPECT_TRUE(cart && bone);

  // calibration (linear): the target in <= 3 solves, within the tolerance
  auto oc = coarse();
  oc.targetElevation = 20.0;
  const nuss::Analysis c = nuss::analyze(surf, lms, oc);
  ASSERT_TRUE(c.calibration.has_value());
  EXPECT_NEAR(c.elevation, 20.0, 0.1);
  EXPECT_LE(c.calibration->evaluations, 3);
  EXPECT_NEAR(c.force, 20.0 / a.linearCompliance, 0.1 / a.linearCompliance);

  // large displacement at a small force stays close to linear (within 3%), and is stiffer
  auto on = coarse();
  on.nonlinear = true;
  on.force = 0.5;
  const nuss::Analysis n = nuss::analyze(surf, lms, on);
  EXPECT_GT(n.elevation, 0.97 * 0.5 * a.linearCompliance);
  EXPECT_LT(n.elevation, 1.01 * 0.5 * a.linearCompliance);
  EXPECT_GE(n.curve.size(), 2u);

  // bad input: each a message naming what to fix
  auto noJoints = lms;
  noJoints.erase(std::remove_if(noJoints.begin(), noJoints.end(), [](const Landmark& l) { return l.code < 300; }), noJoints.end());
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, noJoints, coarse()); }).find("costovertebral joint landmarks"), std::string::npos);
  auto noRib12 = lms;
  noRib12.erase(std::remove_if(noRib12.begin(), noRib12.end(), [](const Landmark& l) { return l.code == 112; }), noRib12.end());
  const std::string e12 = errorOf([&] { nuss::analyze(surf, noRib12, coarse()); });
  EXPECT_NE(e12.find("right rib 12"), std::string::npos) << e12;
  auto noSternum = lms;
  noSternum.erase(std::remove_if(noSternum.begin(), noSternum.end(), [](const Landmark& l) { return l.code == kSternumLowerEnd; }), noSternum.end());
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, noSternum, coarse()); }).find("lower sternum end"), std::string::npos);
  auto space12 = coarse();  // no landmark and no rib 13 to place the exit between
  space12.place.intercostalSpace = 12;
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, lms, space12); }).find("intercostal space 12"), std::string::npos);
  auto unreachable = coarse();
  unreachable.targetElevation = 50.0;
  unreachable.maxForce = 0.5 * 50.0 / a.linearCompliance;
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, lms, unreachable); }).find("reaches the target"), std::string::npos);
  auto badNu = coarse();
  badNu.nuCartilage = 0.5;
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, lms, badNu); }).find("Poisson"), std::string::npos);
  auto badQuality = coarse();  // TetGen's refinement would not terminate: refused before TetGen runs
  badQuality.mesh.radiusEdgeRatio = 1.0;
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, lms, badQuality); }).find("at least 1.2"), std::string::npos);
}

// The tissues' moduli: linear elasticity scales the compliance by 1/k when both moduli scale by k; the
// cartilage carries most of the deformation, so doubling its modulus alone nearly halves the compliance.
TEST(NussAnalysis, TissueModuliScaleTheCompliance) {
  const auto surf = nuss::cageFromMesh(cage().mesh);
  const auto& lms = cage().lms;
  const nuss::Model model = nuss::buildModel(surf, coarse().mesh);
  const double c0 = nuss::analyze(surf, model, lms, coarse()).linearCompliance;
  auto both = coarse();
  both.eBone *= 2, both.eCartilage *= 2;
  const double cBoth = nuss::analyze(surf, model, lms, both).linearCompliance;
  auto cart = coarse();
  cart.eCartilage *= 2;
  const double cCart = nuss::analyze(surf, model, lms, cart).linearCompliance;
  std::printf("compliance %.5f mm/N; both moduli x2: %.5f; cartilage x2: %.5f (ratio %.3f)\n", c0, cBoth, cCart,
              cCart / c0);
  EXPECT_NEAR(cBoth, 0.5 * c0, 1e-6 * c0);
  EXPECT_GT(cCart / c0, 0.5);   // the bone bends a little too
  EXPECT_LT(cCart / c0, 0.6);   // but the cartilage carries most of the deformation
  auto bad = coarse();
  bad.eCartilage = 0;
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, model, lms, bad); }).find("Young's moduli"), std::string::npos);
}

// A joint with fewer than four mesh nodes within the joint radius (a coarse or smoothed mesh) is fixed at the
// four nodes of its own rib nearest to it, and counted; a joint landmark far from every node is refused.
TEST(NussAnalysis, JointWithoutNodesWithinTheRadiusIsFixedAtItsNearestNodes) {
  const auto surf = nuss::cageFromMesh(cage().mesh);
  const auto& lms = cage().lms;
  const nuss::Model model = nuss::buildModel(surf, coarse().mesh);
  const nuss::Analysis a = nuss::analyze(surf, model, lms, coarse());
  auto tiny = coarse();
  tiny.place.jointRadius = 0.05;  // below every joint's nearest-node distance on the coarse cage
  const nuss::Analysis b = nuss::analyze(surf, model, lms, tiny);
  int joints = 0;
  for (const auto& l : lms) joints += (l.code / 100 == 1 || l.code / 100 == 2) && l.code % 100 >= 1 && l.code % 100 <= 12;
  std::printf("joints %d; radius 6 mm: %d widened, %d fixed nodes; radius 0.05 mm: %d widened (up to %.2f mm), %d fixed nodes\n",
              joints, a.jointsWidened, a.fixedAtJoints, b.jointsWidened, b.widestJointRadius, b.fixedAtJoints);
  EXPECT_LT(a.jointsWidened, joints / 4);          // 6 mm holds four nodes at most joints of this coarse TET4 mesh
  EXPECT_EQ(b.jointsWidened, joints);
  EXPECT_GE(b.fixedAtJoints, 4 * joints - 8);      // every joint holds its four nearest nodes (neighbours may share)
  EXPECT_LT(b.fixedAtJoints, a.fixedAtJoints);     // and fewer than the 6 mm radius fixes
  EXPECT_GT(b.widestJointRadius, tiny.place.jointRadius);
  for (int n : b.fixedNodes) EXPECT_EQ(b.result.displacement(n).norm(), 0.0);
  EXPECT_GT(b.elevation, a.elevation);             // fewer fixed nodes: a softer cage
  // each joint's four are nodes of its own rib (a floating rib held by the next rib's nodes would be free)
  std::vector<char> isFixed(b.mesh.nodes.size(), 0);
  for (int n : b.fixedNodes) isFixed[size_t(n)] = 1;
  for (const auto& l : lms) {
    const int side = l.code / 100, rib = l.code % 100;
    if (!(side == 1 || side == 2) || rib < 1 || rib > 12) continue;
    std::vector<int> own;
    for (int t = 0; t < b.mesh.numTets(); ++t)
      if (b.tetPart[size_t(t)] == pectus::ribPart(side, rib))
        for (int k = 0; k < b.mesh.nodesPerTet(); ++k)
          if (const int n = b.mesh.tets[size_t(t)][size_t(k)]; isFixed[size_t(n)]) own.push_back(n);
    std::sort(own.begin(), own.end());
    EXPECT_GE(std::unique(own.begin(), own.end()) - own.begin(), 4) << "joint " << l.code;
  }
  auto far = lms;
  for (auto& l : far)
    if (l.code == 104) l.p.y() -= 100;  // 100 mm behind the right 4th rib's head, behind the whole cage
  const std::string e = errorOf([&] { nuss::analyze(surf, model, far, coarse()); });
  EXPECT_NE(e.find("right rib 4"), std::string::npos) << e;
  EXPECT_NE(e.find("does not belong to this cage"), std::string::npos) << e;
}

namespace {

// the cage without the parts `drop`, plus closed boxes [x0,x0+len] x [0,h] x [z0,z0+h] (one per x0, part
// `parts[i]`, bone) with a vertex every 2 mm along x and only the section's corners across: on a TET10 mesh
// the nodes of a box nearest to a point on the extension of its edge y = 0, z = z0 are that edge's corners
// and mid-edge nodes, all on one line, up to sqrt(d^2 + h^2/4) from it
nuss::CageSurface cageWithBoxes(const nuss::CageSurface& in, const std::vector<int>& drop, const std::vector<double>& x0,
                                const std::vector<double>& len, const std::vector<int>& parts, double z0, double h) {
  nuss::CageSurface c;
  std::vector<int> node(in.surface.V.size(), -1);
  for (size_t f = 0; f < in.surface.F.size(); ++f) {
    if (std::find(drop.begin(), drop.end(), in.facePart[f]) != drop.end()) continue;
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) {
      int& n = node[size_t(in.surface.F[f][k])];
      if (n < 0) n = int(c.surface.V.size()), c.surface.V.push_back(in.surface.V[size_t(in.surface.F[f][k])]);
      t[k] = n;
    }
    c.surface.F.push_back(t);
    c.surface.faceTissue.push_back(in.surface.faceTissue[f]);
    c.facePart.push_back(in.facePart[f]);
  }
  for (size_t b = 0; b < x0.size(); ++b) {
    const int slices = int(std::lround(len[b] / 2.0)) + 1, first = int(c.surface.V.size());
    const double yz[4][2] = {{0, 0}, {h, 0}, {h, h}, {0, h}};
    for (int i = 0; i < slices; ++i)
      for (const auto& q : yz) c.surface.V.emplace_back(x0[b] + 2.0 * i, q[0], z0 + q[1]);
    auto v = [&](int i, int k) { return first + 4 * i + (k % 4); };
    auto face = [&](int a, int b2, int c2) {
      c.surface.F.push_back({a, b2, c2});
      c.surface.faceTissue.push_back(int(Tissue::Bone));
      c.facePart.push_back(parts[b]);
    };
    for (int i = 0; i + 1 < slices; ++i)
      for (int k = 0; k < 4; ++k) face(v(i, k), v(i + 1, k), v(i + 1, k + 1)), face(v(i, k), v(i + 1, k + 1), v(i, k + 1));
    face(v(0, 0), v(0, 2), v(0, 1)), face(v(0, 0), v(0, 3), v(0, 2));
    face(v(slices - 1, 0), v(slices - 1, 1), v(slices - 1, 2)), face(v(slices - 1, 0), v(slices - 1, 2), v(slices - 1, 3));
  }
  return c;
}

// mm: the largest distance of the points from the line through the first and the farthest from it
double spreadOffLine(const std::vector<Eigen::Vector3d>& p) {
  double far = 0, off = 0;
  Eigen::Vector3d b = p.front();
  for (const auto& q : p)
    if ((q - p.front()).norm() > far) far = (q - p.front()).norm(), b = q;
  if (!(far > 0)) return 0;
  const Eigen::Vector3d d = (b - p.front()) / far;
  for (const auto& q : p) off = std::max(off, (q - p.front() - (q - p.front()).dot(d) * d).norm());
  return off;
}

}  // namespace

// A floating rib is held only at its joint. On a TET10 mesh the rib's nodes nearest to the joint can all lie on
// one line (two corners of an edge pointing at the joint, the mid-edge node between them and the next one
// along), and the rib then turns about that line: the stiffness matrix is singular. The joint fixes its rib's
// nearest nodes until they leave one line. A piece held by other joints' nodes on one line only is refused.
TEST(NussAnalysis, FloatingRibIsNotHeldOnOneLine) {
  const auto surf = nuss::cageFromMesh(cage().mesh);
  const double z0 = 2000, h = 12;  // far above the cage
  auto o = coarse();
  o.mesh.order = 2;
  // the right rib 11 (a floating rib) replaced by a box; its joint 2.5 mm beyond the box's end on the line
  // of its edge y = 0, z = z0: the nodes within the joint radius (6 mm) are that edge's first four nodes
  auto lms = cage().lms;
  for (auto& l : lms)
    if (l.code == ribPart(1, 11)) l.p = Eigen::Vector3d(-2.5, 0, z0);
  const auto one = cageWithBoxes(surf, {ribPart(1, 11)}, {0.0}, {20.0}, {ribPart(1, 11)}, z0, h);
  nuss::Analysis a;
  ASSERT_NO_THROW(a = nuss::analyze(one, lms, o));
  std::vector<char> isFixed(a.mesh.nodes.size(), 0);
  for (int n : a.fixedNodes) isFixed[size_t(n)] = 1;
  std::vector<Eigen::Vector3d> held;
  for (int t = 0; t < a.mesh.numTets(); ++t)
    if (a.tetPart[size_t(t)] == ribPart(1, 11))
      for (int k = 0; k < a.mesh.nodesPerTet(); ++k)
        if (const int n = a.mesh.tets[size_t(t)][size_t(k)]; isFixed[size_t(n)]) {
          held.push_back(a.mesh.nodes[size_t(n)]);
          isFixed[size_t(n)] = 0;
        }
  ASSERT_GE(held.size(), 5u);
  EXPECT_GT(spreadOffLine(held), 1.0) << held.size() << " fixed nodes of the box";
  EXPECT_TRUE(a.result.u.allFinite());

  // a second box, of a part without a joint, 2.5 mm on the other side of that joint: the joint's radius
  // reaches four nodes of it, all on one line, and nothing else holds it
  const auto two = cageWithBoxes(surf, {ribPart(1, 11)}, {0.0, -25.0}, {20.0, 20.0}, {ribPart(1, 11), 0}, z0, h);
  const std::string e = errorOf([&] { nuss::analyze(two, lms, o); });
  EXPECT_NE(e.find("on one line"), std::string::npos) << e;
  EXPECT_NE(e.find("increase the joint radius"), std::string::npos) << e;
}

// The sternoclavicular support holds the anterior translation of the sternum's nodes near the jugular notch
// and nothing else: those nodes keep their other translations, the lifted sternum no longer turns about its
// middle (the notch's nodes moved back without it), and the same force lifts the lower end less. Without the
// notch landmark, or with no sternum node within the radius, the analysis is refused with what to change.
TEST(NussAnalysis, SternoclavicularSupportHoldsTheManubriumForwardOnly) {
  const auto surf = nuss::cageFromMesh(cage().mesh);
  const auto& lms = cage().lms;
  const nuss::Model model = nuss::buildModel(surf, coarse().mesh);
  const nuss::Analysis free = nuss::analyze(surf, model, lms, coarse());
  auto held = coarse();
  held.place.sternoclavicularRadius = 12;
  const nuss::Analysis a = nuss::analyze(surf, model, lms, held);
  ASSERT_FALSE(a.sternoclavicularNodes.empty());
  double yFree = 0, other = 0;
  for (int n : a.sternoclavicularNodes) {
    EXPECT_EQ(a.result.displacement(n).y(), 0.0);
    yFree += free.result.displacement(n).y() / double(a.sternoclavicularNodes.size());
    other = std::max(other, std::abs(a.result.displacement(n).z()));
  }
  std::printf("sternoclavicular nodes %zu; their mean anterior displacement without the support %.4f mm, largest vertical "
              "with it %.4f mm; elevation at 10 N %.4f mm free, %.4f mm held\n",
              a.sternoclavicularNodes.size(), yFree, other, free.elevation, a.elevation);
  EXPECT_LT(yFree, 0.0);               // free, the upper sternum moves back as the lower end rises
  EXPECT_GT(other, 0.0);               // held only along the force: the other translations stay free
  EXPECT_LT(a.elevation, 0.8 * free.elevation);
  EXPECT_EQ(a.fixedNodes.size(), free.fixedNodes.size());
  auto noNotch = lms;
  noNotch.erase(std::remove_if(noNotch.begin(), noNotch.end(), [](const Landmark& l) { return l.code == kSternumUpperEnd; }),
                noNotch.end());
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, model, noNotch, held); }).find("jugular notch (landmark 502)"), std::string::npos);
  auto tiny = held;
  tiny.place.sternoclavicularRadius = 1e-3;
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, model, lms, tiny); }).find("increase the sternoclavicular radius"), std::string::npos);
  auto bad = held;
  bad.place.sternoclavicularRadius = -1;
  EXPECT_NE(errorOf([&] { nuss::analyze(surf, model, lms, bad); }).find("sternoclavicular support radius"), std::string::npos);
}

// validate() checks the options against the ranges the filters declare (nuss_analysis.h)
TEST(NussAnalysis, ValidateChecksTheDeclaredRanges) {
  const nuss::Options ok;
  EXPECT_NO_THROW(nuss::validate(ok));
  auto refused = [&](auto change, const std::string& words) {
    nuss::Options o = ok;
    change(o);
    EXPECT_NE(errorOf([&] { nuss::validate(o); }).find(words), std::string::npos) << words;
  };
  refused([](nuss::Options& o) { o.force = nuss::kForceRange.hi * 2; }, "elevating force must lie in (0, 100000] N");
  refused([](nuss::Options& o) { o.maxForce = 0; }, "maximum force must lie in (0, 1e+06] N");
  refused([](nuss::Options& o) { o.tolerance = 51; }, "calibration tolerance must lie in (0, 50] mm");
  refused([](nuss::Options& o) { o.targetElevation = -1; }, "target elevation must lie in [0, 300] mm");
  nuss::Options calibrated = ok;  // the force is not used when calibrating
  calibrated.targetElevation = 20;
  calibrated.force = 0;
  EXPECT_NO_THROW(nuss::validate(calibrated));
}

TEST(NussAnalysis, UnlabelledOrEmptyLayersAreRefused) {
  pectus::OwnedMesh m;
  EXPECT_NE(errorOf([&] { nuss::cageFromMesh(m); }).find("no faces"), std::string::npos);
  vcg::tri::Append<CMeshO, CMeshO>::MeshCopy(m, cage().mesh);  // copies geometry, not the label attributes
  m.face.DisableColor();
  m.face.DisableQuality();
  EXPECT_NE(errorOf([&] { nuss::cageFromMesh(m); }).find("no tissue labels"), std::string::npos);
}

TEST(NussAnalysis, MicroEdgesAreWelded) {
  // a tetrahedron with one vertex split into two 1e-6 apart (a sliver tent): welded back to 4 faces
  pectus::OwnedMesh m;
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(m, 5);
  const float P[5][3] = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}, {0, 0, 10.000001f}};
  for (int i = 0; i < 5; ++i) vi[i].P() = Point3m(P[i][0], P[i][1], P[i][2]);
  auto add = [&](int a, int b, int c) { vcg::tri::Allocator<CMeshO>::AddFace(m, &m.vert[a], &m.vert[b], &m.vert[c]); };
  add(0, 2, 1);
  add(0, 1, 3);
  add(1, 2, 4);
  add(2, 0, 3);
  add(1, 4, 3);  // degenerate after welding 3-4
  add(2, 3, 4);  // degenerate after welding 3-4
  writeFaceLabels(m, std::vector<int>(m.face.size(), 1), std::vector<int>(m.face.size(), 101));
  const auto c = nuss::cageFromMesh(m);
  EXPECT_EQ(c.surface.V.size(), 4u);
  EXPECT_EQ(c.surface.F.size(), 4u);
  EXPECT_EQ(c.nodeOfVertex[3], c.nodeOfVertex[4]);
  EXPECT_EQ(c.weldedFaces, 2);
}

TEST(NussAnalysis, UnreferencedVerticesAreDropped) {
  // the cage plus stray vertices no face uses (one far outside, one inside a rib): they are not FE nodes,
  // so the stiffness stays positive definite and the analysis gives the cage's own answer
  const auto ref = nuss::analyze(nuss::cageFromMesh(cage().mesh), cage().lms, coarse());
  pectus::OwnedMesh m;
  copyLabelledMesh(m, cage().mesh);
  auto vi = vcg::tri::Allocator<CMeshO>::AddVertices(m, 2);
  vi[0].P() = Point3m(500, 500, 500);
  vi[1].P() = m.face[0].cP(0);
  const auto c = nuss::cageFromMesh(m);
  EXPECT_EQ(c.unreferencedVertices, 2);
  EXPECT_EQ(c.nodeOfVertex[m.vert.size() - 1], -1);
  EXPECT_EQ(c.nodeOfVertex[m.vert.size() - 2], -1);
  const auto a = nuss::analyze(c, cage().lms, coarse());
  EXPECT_EQ(a.mesh.numNodes(), ref.mesh.numNodes());
  EXPECT_NEAR(a.elevation, ref.elevation, 1e-9 * ref.elevation);
}

TEST(NussAnalysis, TissueLayersJoinedIntoTheCagesVolume) {
  // the same cage as three overlapping tissue surfaces (as CT segmentation exports them), joined by the
  // corefinement union: one closed model with the labelled cage's pieces (the cage + 4 floating ribs) and
  // volume, all three tissues, and an analysis that runs on it
  ribcage::RibCageParams p;
  p.edgeLength = 6.0;
  std::array<pectus::OwnedMesh, 3> layers;
  const auto lms = ribcage::generateTissueLayers(p, layers);
  pectus::OwnedMesh joined;
  nuss::JoinStats st;
  const auto& name = ribcage::kTissueLayerNames;
  const auto surf = nuss::joinTissueLayers({{name[0], &layers[0]}, {name[1], &layers[1]}, {name[2], &layers[2]}}, lms, joined, &st);
  EXPECT_LT(st.unionVolume, st.sumVolume);  // the layers overlap
  EXPECT_EQ(st.components, 5);
  const auto a = nuss::analyze(surf, lms, coarse());
  const auto ref = nuss::analyze(nuss::cageFromMesh(cage().mesh), cage().lms, coarse());
  double vRef = 0;
  for (int t = 0; t < ref.mesh.numTets(); ++t) vRef += ref.mesh.tetVolume(t);
  std::printf("[tissue layers] %zu faces, volume %.1f cm3 (layers %.1f, labelled cage %.1f), TET4 elevation %.3f mm vs labelled cage "
              "%.3f mm (%d vs %d tets)\n",
              surf.surface.F.size(), st.unionVolume / 1000, st.sumVolume / 1000, vRef / 1000, a.elevation, ref.elevation,
              a.mesh.numTets(), ref.mesh.numTets());
  EXPECT_NEAR(st.unionVolume, vRef, 0.03 * vRef);
  EXPECT_GT(a.elevation, 0);
  std::array<int, 4> n{};
  for (int t = 0; t < a.mesh.numTets(); ++t) n[std::size_t(a.mesh.tissue[std::size_t(t)])]++;
  EXPECT_GT(n[1], 0);
  EXPECT_GT(n[2], 0);
  EXPECT_GT(n[3], 0);
  EXPECT_EQ(n[0], 0);
}

// calibration by prescribed elevation: one displacement-controlled solve lands on the target and finds
// the force the force search finds (within what its 0.1 mm tolerance allows); the neo-Hookean tissues
// calibrate the same way; unknown names of a material or a method are refused with the choices
TEST(NussAnalysis, DisplacementControlCalibratesInOneSolve) {
  const auto surf = nuss::cageFromMesh(cage().mesh);
  const auto& lms = cage().lms;
  auto o = coarse();
  o.nonlinear = true;
  o.targetElevation = 10.0;
  const nuss::Model model = nuss::buildModel(surf, o.mesh);
  const nuss::Analysis search = nuss::analyze(surf, model, lms, o);
  o.calibration = nuss::CalibrationMethod::DisplacementControl;
  const nuss::Analysis control = nuss::analyze(surf, model, lms, o);
  std::printf("[nuss control] force search: %.4f N at %.4f mm, %d solves, %d iterations, %.2f s; displacement control: "
              "%.4f N at %.4f mm, %d solve, %d iterations, %.2f s\n",
              search.force, search.elevation, search.nonlinearSolves, search.newtonIterations, search.secondsSolve, control.force,
              control.elevation, control.nonlinearSolves, control.newtonIterations, control.secondsSolve);
  EXPECT_EQ(control.nonlinearSolves, 1);
  EXPECT_NEAR(control.elevation, 10.0, 1e-4);
  ASSERT_TRUE(control.calibration.has_value());
  EXPECT_EQ(control.calibration->evaluations, 1);
  // the search stops within 0.1 mm of the target: its force is off by at most 0.1 mm over the local slope
  const double slope = (search.curve.back().second - search.curve.front().second) / search.curve.back().first;  // mm/N, secant
  EXPECT_NEAR(control.force, search.force, 0.1 / slope * 1.5);
  EXPECT_GT(control.force, 0.0);
  ASSERT_GE(control.curve.size(), 3u);
  for (std::size_t k = 1; k < control.curve.size(); ++k) EXPECT_GT(control.curve[k].second, control.curve[k - 1].second);
  o.material = fe::MaterialModel::NeoHookean;
  o.newton.lineSearch = true;
  o.newton.adaptiveSteps = true;
  const nuss::Analysis neo = nuss::analyze(surf, model, lms, o);
  std::printf("[nuss control] neo-Hookean: %.4f N at %.4f mm, %d iterations\n", neo.force, neo.elevation, neo.newtonIterations);
  EXPECT_NEAR(neo.elevation, 10.0, 1e-4);
  EXPECT_NEAR(neo.force / control.force, 1.0, 0.1);  // the same small-strain limit; strains of a few %
  EXPECT_NE(errorOf([] { nuss::parseCalibrationMethod("arc"); }).find("displacement"), std::string::npos);
  EXPECT_NE(errorOf([] { fe::parseMaterialModel("mooney"); }).find("neo-hookean"), std::string::npos);
}

// The chest line target: on the default cage (funnel centred around the lower sternum end) the depth is the
// generator's funnel (the lower end lies behind the most anterior rib points at its level), the target
// from the model is that depth, and a target past the reach is refused before TetGen; a cage whose funnel
// is centred on the sternal body (its lower end at the chest line) has no depression to correct there.
TEST(NussAnalysis, ChestLineTargetAndReach) {
  const ribcage::RibCageStats& st = cage().stats;
  const auto surf = nuss::cageFromMesh(cage().mesh);
  const auto& lms = cage().lms;
  const nuss::ChestLine c = nuss::chestLine(surf, lms, nuss::Placement{});
  EXPECT_GT(c.depth, 0.6 * st.funnelDepth);
  EXPECT_LT(c.depth, 1.2 * st.funnelDepth);
  EXPECT_LT(c.right.x(), -nuss::kChestLineGap);
  EXPECT_GT(c.left.x(), nuss::kChestLineGap);
  EXPECT_NEAR(c.right.y(), c.left.y(), 5.0);  // the generated cage is symmetric

  auto o = coarse();
  o.targetFromChestLine = true;
  const nuss::Target t = nuss::resolveTarget(surf, lms, o);
  EXPECT_TRUE(t.fromChestLine);
  EXPECT_DOUBLE_EQ(t.elevation, c.depth);
  EXPECT_NE(t.describe().find("from the model"), std::string::npos) << t.describe();
  const nuss::Analysis a = nuss::analyze(surf, lms, o);  // small strain: calibrated exactly
  EXPECT_NEAR(a.elevation, c.depth, 1e-6 * c.depth);
  EXPECT_DOUBLE_EQ(a.target.elevation, c.depth);

  auto far = coarse();
  far.targetElevation = c.reach() + 1.0;
  const std::string e = errorOf([&] { nuss::analyze(surf, lms, far); });
  EXPECT_NE(e.find("reachable targets are (0, "), std::string::npos) << e;
  far.targetElevation = c.reach() - 1.0;
  EXPECT_NO_THROW(nuss::resolveTarget(surf, lms, far));

  // the funnel on the sternal body: the lower sternum end lies at the chest line, so the model gives no target
  ribcage::RibCageParams p;
  p.edgeLength = 6.0;
  p.funnelCenterZ = 0.8;
  OwnedMesh body;
  const auto bodyLms = ribcage::generateRibCage(p, body);
  auto fromModel = coarse();
  fromModel.targetFromChestLine = true;
  const std::string flat = errorOf([&] { nuss::resolveTarget(nuss::cageFromMesh(body), bodyLms, fromModel); });
  EXPECT_NE(flat.find("no depression to correct"), std::string::npos) << flat;
}

TEST(NussOutput, OneWriterForTheFilesAndTheDeformedSurface) {
  const auto surf = nuss::cageFromMesh(cage().mesh);
  const auto o = coarse();
  const nuss::Analysis a = nuss::analyze(surf, cage().lms, o);
  const std::string dir = ::testing::TempDir();
  const std::string base = nuss::resultBase(dir + "/nuss_output.vtu");
  EXPECT_EQ(base, dir + "/nuss_output");
  const nuss::OutputFiles files = nuss::filesAt(base, 2, 5);
  EXPECT_EQ(files.ribStrainCsv, base + "_rib_strain.csv");
  nuss::writeOutputs(files, a, o);
  auto text = [](const std::string& path) {
    std::string s;
    if (std::FILE* f = std::fopen(path.c_str(), "r")) {
      char b[4096];
      for (size_t n; (n = std::fread(b, 1, sizeof b, f)) > 0;) s.append(b, n);
      std::fclose(f);
    }
    return s;
  };
  EXPECT_NE(text(files.vtu).find("<VTKFile"), std::string::npos);
  const std::string inp = text(files.inp);
  EXPECT_NE(inp.find("*HEADING\npectus-meshlab Nuss FE model, Fe = 10.00 N\n"), std::string::npos);
  EXPECT_EQ(inp.find("NLGEOM"), std::string::npos);  // small strain
  EXPECT_EQ(text(files.curveCsv).rfind("force_N,elevation_mm\n", 0), 0u);
  EXPECT_EQ(text(files.ribStrainCsv).rfind("distance_from_sternum_midline_mm,", 0), 0u);
  // the deck's increments follow the curve step: one per step of the final force, 10 at least
  nuss::Options big = o;
  big.nonlinear = true;
  nuss::Analysis b = a;
  b.force = 430;
  EXPECT_EQ(nuss::inpOptions(b, big).increments, 22);
  EXPECT_TRUE(nuss::inpOptions(b, big).nlgeom);
  b.force = 10;
  EXPECT_EQ(nuss::inpOptions(b, big).increments, 10);
  // an empty path writes nothing; an unwritable one names the path
  nuss::OutputFiles none;
  nuss::writeOutputs(none, a, o);
  nuss::OutputFiles bad;
  bad.curveCsv = "/nonexistent-dir/curve.csv";
  EXPECT_NE(errorOf([&] { nuss::writeOutputs(bad, a, o); }).find("/nonexistent-dir/curve.csv"), std::string::npos);

  // the deformed surface: the analysed mesh's vertices moved by their nodes, quality = the nodal field
  pectus::OwnedMesh out;
  out.face.EnableColor();
  out.face.EnableQuality();
  nuss::deformedSurface(out, cage().mesh, surf, a, a.nodalStress);
  ASSERT_EQ(out.vn, cage().mesh.vn);
  ASSERT_EQ(out.fn, cage().mesh.fn);
  double moved = 0;
  for (size_t i = 0, k = 0; i < cage().mesh.vert.size(); ++i) {
    if (cage().mesh.vert[i].IsD()) continue;
    const int n = surf.nodeOfVertex[i];
    const auto& v = out.vert[k++];
    if (n < 0) continue;
    const Eigen::Vector3d d = a.result.displacement(n);
    EXPECT_NEAR(v.cP()[1], cage().mesh.vert[i].cP()[1] + d.y(), 1e-3);
    EXPECT_FLOAT_EQ(v.cQ(), float(a.nodalStress[std::size_t(n)]));
    moved = std::max(moved, d.norm());
  }
  EXPECT_GT(moved, 0.0);
  EXPECT_TRUE(readFaceLabels(out).has_value());  // the tissue labels stay
}

// The analysis names what keeps a result from being one to report: the FE filter logs it and returns
// reportable 0. The converged settings (TET10, quality refinement) on a surface of the convergence study's
// edges say nothing; each coarser choice is named.
TEST(NussAnalysis, ResultOnACoarserMeshThanTheConvergedOneSaysWhy) {
  auto surf = nuss::cageFromMesh(cage().mesh);  // 6 mm edges: coarser than the study's 5 mm cage
  fe::TetgenOptions converged;
  converged.order = 2;
  converged.radiusEdgeRatio = 2.0;
  const std::string coarseSurface = nuss::notReportableBecause(converged, surf);
  EXPECT_NE(coarseSurface.find("surface edges of"), std::string::npos) << coarseSurface;
  EXPECT_EQ(coarseSurface.find("TET4"), std::string::npos) << coarseSurface;

  for (auto& v : surf.surface.V) v *= 0.5;  // the same cage at half the size: edges of about 3.4 mm
  EXPECT_EQ(nuss::notReportableBecause(converged, surf), "");
  fe::TetgenOptions quick = converged;
  quick.order = 1;
  quick.radiusEdgeRatio = 0;
  const std::string why = nuss::notReportableBecause(quick, surf);
  EXPECT_NE(why.find("linear TET4 locks in bending"), std::string::npos) << why;
  EXPECT_NE(why.find("tet quality 0"), std::string::npos) << why;
}
