// The preparation of a patient's rib cage, on the generator's own cage exported one layer per tissue
// (as segmentation tools export them), moved into a scanner frame: the prepared cage must come back
// numbered, labelled and landmarked like the generator's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>

#include <vcg/complex/algorithms/create/platonic.h>

#include "pectus/errors.h"
#include "pectus/patient/prepare.h"
#include "pectus/ribcage/ribcage.h"
#include "pectus/patient/soup.h"
#include "temp_dir.h"

using namespace pectus;
using namespace pectus::patient;

namespace {
struct Exported {
  std::array<OwnedMesh, 3> layers;
  std::vector<Landmark> truth;
};
// the generated cage's three tissue layers; coordinates mapped p -> M p + t
const Exported& exported() {
  static Exported e;
  static const bool made = [] {
    ribcage::RibCageParams p;
    p.age = 7;
    p.edgeLength = 3.0;
    e.truth = ribcage::generateTissueLayers(p, e.layers);
    return true;
  }();
  (void)made;
  return e;
}
void mapInto(const CMeshO& src, OwnedMesh& dst, const Eigen::Matrix3d& M, const Eigen::Vector3d& t) {
  copyLabelledMesh(dst, const_cast<CMeshO&>(src));
  for (auto& v : dst.vert) v.P() = toPoint(M * toEigen(v.P()) + t);
}
std::vector<InputLayer> inputs(std::array<OwnedMesh, 3>& m) {
  return {{"ribs", &m[0]}, {"costal cartilage", &m[1]}, {"sternum", &m[2]}};
}
const Landmark* find(const std::vector<Landmark>& l, int code) {
  for (const auto& x : l)
    if (x.code == code) return &x;
  return nullptr;
}
bool logHas(const PrepareResult& r, const std::string& words) {
  return std::any_of(r.log.begin(), r.log.end(), [&](const std::string& l) { return l.find(words) != std::string::npos; });
}
// the connected pieces of m, one mesh each
std::vector<std::unique_ptr<OwnedMesh>> piecesOf(const CMeshO& m) {
  Soup s = surfaceOf(m, kFiniteFaces);
  weld(s);
  std::vector<std::unique_ptr<OwnedMesh>> out;
  for (const auto& p : components(s)) {
    out.push_back(std::make_unique<OwnedMesh>());
    toMesh(p, *out.back());
  }
  return out;
}
// the layers mapped into a scanner frame: RAS, mm, an offset origin
void toScanner(std::array<OwnedMesh, 3>& m) {
  const auto& e = exported();
  const Eigen::Matrix3d M = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  for (int k = 0; k < 3; ++k) mapInto(e.layers[std::size_t(k)], m[std::size_t(k)], M, Eigen::Vector3d(120, -35, 800));
}
using pectus::patient::testing::errorOf;
}  // namespace

TEST(PatientNames, TotalSegmentatorSlicerAndGenericNames) {
  EXPECT_EQ(classifyName("rib_left_3").kind, Kind::Rib);
  EXPECT_EQ(classifyName("rib_left_3").side, 2);
  EXPECT_EQ(classifyName("rib_left_3").number, 3);
  EXPECT_EQ(classifyName("Rib R 11").side, 1);
  EXPECT_EQ(classifyName("Rib R 11").number, 11);
  EXPECT_EQ(classifyName("right rib12").number, 12);
  EXPECT_EQ(classifyName("costal_cartilages").kind, Kind::Cartilage);
  EXPECT_EQ(classifyName("costal cartilage").kind, Kind::Cartilage);
  EXPECT_EQ(classifyName("sternum").kind, Kind::Sternum);
  EXPECT_EQ(classifyName("vertebrae_T5").kind, Kind::Vertebra);
  EXPECT_EQ(classifyName("bone").kind, Kind::Bone);
  EXPECT_EQ(classifyName("ribs").kind, Kind::Bone);
  EXPECT_EQ(classifyName("scapula_left").kind, Kind::NotCage);
  EXPECT_EQ(classifyName("clavicula_right").kind, Kind::NotCage);
  EXPECT_EQ(classifyName("liver").kind, Kind::NotCage);
  EXPECT_EQ(classifyName("Segment_7").kind, Kind::Unknown);
  EXPECT_EQ(classifyName("closed_valid").kind, Kind::Unknown);
  // every other class of a TotalSegmentator label map is named as such: never left to its shape (never a
  // candidate sternum)
  for (const char* organ : {"colon", "pancreas", "small_bowel", "duodenum", "gallbladder", "urinary_bladder", "spinal_cord",
                            "autochthon_left", "iliopsoas_right", "portal_vein_and_splenic_vein", "inferior_vena_cava"})
    EXPECT_EQ(classifyName(organ).kind, Kind::NotCage) << organ;
}

// The generated cage in RAS, metres, with an offset origin: units, frame, numbering, landmarks recovered.
TEST(PatientPrepare, GeneratedCageInRasMetres) {
  const auto& e = exported();
  std::array<OwnedMesh, 3> m;
  Eigen::Matrix3d M = Eigen::Vector3d(-0.001, 0.001, 0.001).asDiagonal();  // ours (L, A, S) mm -> RAS m
  const Eigen::Vector3d t(0.12, -0.035, 0.8);
  for (int k = 0; k < 3; ++k) mapInto(e.layers[std::size_t(k)], m[std::size_t(k)], M, t);
  PrepareOptions o;
  o.edgeLength = 3.0;
  OwnedMesh cage;
  const auto r = preparePatientCage(inputs(m), o, cage);
  for (const auto& l : r.log) std::printf("  %s\n", l.c_str());
  EXPECT_EQ(r.ribsRight, 12);
  EXPECT_EQ(r.ribsLeft, 12);
  ASSERT_TRUE(readFaceLabels(cage));
  // the result is in the project frame up to a shift: compare landmark to landmark after removing the
  // shift of the lower sternum end
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (int side = 1; side <= 2; ++side)
    for (int rib = 1; rib <= 12; ++rib) {
      const Landmark* a = find(e.truth, cvjLandmark(side, rib));
      const Landmark* b = find(r.landmarks, cvjLandmark(side, rib));
      ASSERT_TRUE(a && b) << "joint " << cvjLandmark(side, rib);
      d += (b->p - a->p) / 24.0;
    }
  for (const auto& l : r.landmarks)
    if (const Landmark* a = find(e.truth, l.code))
      std::printf("  %d truth (%.1f %.1f %.1f) prepared-shift (%.1f %.1f %.1f)\n", l.code, a->p.x(), a->p.y(), a->p.z(),
                  l.p.x() - d.x(), l.p.y() - d.y(), l.p.z() - d.z());
  for (int side = 1; side <= 2; ++side)
    for (int rib = 1; rib <= 12; ++rib) {
      const Landmark* a = find(e.truth, cvjLandmark(side, rib));
      const Landmark* b = find(r.landmarks, cvjLandmark(side, rib));
      ASSERT_TRUE(a && b) << "joint " << cvjLandmark(side, rib);
      EXPECT_LT((b->p - d - a->p).norm(), 3.0) << "joint " << cvjLandmark(side, rib);
    }
  const Landmark* deep0 = find(e.truth, kFunnelDeepest);
  const Landmark* deep1 = find(r.landmarks, kFunnelDeepest);
  ASSERT_TRUE(deep0 && deep1);
  EXPECT_LT((deep1->p - d - deep0->p).norm(), 12.0);
  for (int code : {barExitLandmark(1, 4), barExitLandmark(1, 5), barExitLandmark(2, 4), barExitLandmark(2, 5)}) {
    const Landmark* a = find(e.truth, code);
    const Landmark* b = find(r.landmarks, code);
    ASSERT_TRUE(a && b) << "bar exit " << code;
    EXPECT_LT((b->p - d - a->p).norm(), 5.0) << "bar exit " << code;
  }
  EXPECT_TRUE(find(r.landmarks, kDiaphragmDome) && find(r.landmarks, kLungApex));
}

TEST(PatientPrepare, RefusesWithoutSternumCartilageOrOneSide) {
  const auto& e = exported();
  std::array<OwnedMesh, 3> m;
  for (int k = 0; k < 3; ++k) mapInto(e.layers[std::size_t(k)], m[std::size_t(k)], Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  OwnedMesh cage;
  auto expectError = [&](std::vector<InputLayer> in, const std::string& words, PrepareOptions o = {}) {
    try {
      preparePatientCage(in, o, cage);
      ADD_FAILURE() << "no error, expected: " << words;
    } catch (const InputError& x) {
      EXPECT_NE(std::string(x.what()).find(words), std::string::npos) << x.what();
    }
  };
  expectError({{"ribs", &m[0]}, {"costal cartilage", &m[1]}}, "No sternum");
  expectError({{"ribs", &m[0]}, {"sternum", &m[2]}}, "No costal cartilage");
  // no sternum by name, and none by shape: the ribs and the cartilages alone
  expectError({{"Segment_1", &m[0]}, {"Segment_2", &m[1]}}, "Rename the layers");
  // a 'sternum' at the centre of the bone: no anterior direction
  expectError({{"ribs", &m[0]}, {"costal cartilage", &m[1]}, {"sternum", &m[0]}}, "Cannot find the anatomical frame");
  // the right ribs only: drop every face on the left
  OwnedMesh right;
  mapInto(e.layers[0], right, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  for (auto& f : right.face)
    if ((f.cP(0)[0] + f.cP(1)[0] + f.cP(2)[0]) > 0) vcg::tri::Allocator<CMeshO>::DeleteFace(right, f);
  PrepareOptions stated;
  stated.frame = FrameMode::Model;  // one side only: the anterior direction from the anatomy leans to that side
  expectError({{"ribs", &right}, {"costal cartilage", &m[1]}, {"sternum", &m[2]}}, "side only", stated);
}

TEST(PatientPrepare, PickedPointsFile) {
  const std::string path = ::testing::TempDir() + "/picked.pp";
  std::ofstream(path) << "<!DOCTYPE PickedPoints>\n<PickedPoints>\n <DocumentData/>\n"
                         " <point x=\"1.5\" y=\"2\" z=\"-3\" active=\"1\" name=\"500 lower sternum end\"/>\n"
                         " <point x=\"4\" y=\"5\" z=\"6\" active=\"0\" name=\"501\"/>\n"
                         " <point x=\"7\" y=\"8\" z=\"9\" active=\"1\" name=\"apex\"/>\n</PickedPoints>\n";
  int skipped = 0;
  const auto p = readPickedPoints(path, &skipped);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].code, 500);
  EXPECT_DOUBLE_EQ(p[0].p.x(), 1.5);
  EXPECT_EQ(skipped, 2);
  EXPECT_THROW(readPickedPoints(::testing::TempDir() + "/none.pp"), InputError);
}

// The generator's layers named as a 3D Slicer export names segments ('Segment_1', ...), the ribs one layer each
// (as TotalSegmentator's labels give them): classified by their shape, numbered by their place, and prepared to
// the cage the names give.
TEST(PatientPrepare, UnnamedLayersClassifiedByShape) {
  std::array<OwnedMesh, 3> m;
  toScanner(m);
  PrepareOptions o;
  o.edgeLength = 3.0;
  OwnedMesh named, unnamed;
  const auto r0 = preparePatientCage(inputs(m), o, named);
  const auto ribs = piecesOf(m[0]);
  ASSERT_EQ(ribs.size(), 24u);
  // the order of a segmentation's segments says nothing: cartilage first, the sternum among the ribs
  std::vector<InputLayer> in{{"Segment_1", &m[1]}};
  for (std::size_t k = 0; k < ribs.size(); ++k) {
    if (k == 9) in.push_back({"Segment_" + std::to_string(in.size() + 1), &m[2]});
    in.push_back({"Segment_" + std::to_string(in.size() + 1), ribs[k].get()});
  }
  const auto r1 = preparePatientCage(in, o, unnamed);
  for (const auto& l : r1.log)
    if (l.find("by its shape") != std::string::npos) std::printf("  %s\n", l.c_str());
  EXPECT_TRUE(logHas(r1, "'Segment_1': costal cartilage (by its shape"));
  EXPECT_TRUE(logHas(r1, "'Segment_11': sternum (by its shape"));
  EXPECT_TRUE(logHas(r1, "'Segment_2': rib (by its shape"));
  EXPECT_EQ(r1.ribsRight, 12);
  EXPECT_EQ(r1.ribsLeft, 12);
  double worst = 0;
  for (int side = 1; side <= 2; ++side)
    for (int rib = 1; rib <= 12; ++rib) {
      const Landmark* a = find(r0.landmarks, cvjLandmark(side, rib));
      const Landmark* b = find(r1.landmarks, cvjLandmark(side, rib));
      ASSERT_TRUE(a && b) << "joint " << cvjLandmark(side, rib);
      worst = std::max(worst, (b->p - a->p).norm());
    }
  std::printf("  costovertebral joints, by shape vs by name: at most %.3f mm apart\n", worst);
  EXPECT_LT(worst, 2.0);
  for (int code : {kSternumLowerEnd, kFunnelDeepest}) {
    const Landmark* a = find(r0.landmarks, code);
    const Landmark* b = find(r1.landmarks, code);
    ASSERT_TRUE(a && b) << code;
    EXPECT_LT((b->p - a->p).norm(), 2.0) << code;
  }
}

// Layers whose names say nothing and whose shapes settle nothing are refused with what to rename: two blobs,
// and the generator's layers with two equally good sternums.
TEST(PatientPrepare, RefusesShapesThatSettleNothing) {
  OwnedMesh sphere, box;
  vcg::tri::Sphere(sphere, 3);
  vcg::tri::Box(box, vcg::Box3<CMeshO::ScalarType>(Point3m(-20, -30, -40), Point3m(60, 50, 40)));
  for (auto& v : sphere.vert) v.P() = v.P() * 50.0f;
  OwnedMesh cage;
  const std::string blobs = errorOf([&] { preparePatientCage({{"Segment_1", &sphere}, {"Segment_2", &box}}, {}, cage); });
  EXPECT_NE(blobs.find("Cannot tell the rib cage's structures from the shapes"), std::string::npos) << blobs;
  EXPECT_NE(blobs.find("'Segment_1', 'Segment_2'"), std::string::npos) << blobs;
  EXPECT_NE(blobs.find("costal cartilages"), std::string::npos) << blobs;
  EXPECT_NE(blobs.find("Rename the layers: 'sternum', 'costal_cartilages'"), std::string::npos) << blobs;

  std::array<OwnedMesh, 3> m;
  toScanner(m);
  const std::string twice = errorOf([&] {
    preparePatientCage({{"Segment_1", &m[0]}, {"Segment_2", &m[1]}, {"Segment_3", &m[2]}, {"Segment_4", &m[2]}}, {}, cage);
  });
  EXPECT_NE(twice.find("'Segment_3' and 'Segment_4' are equally good sternums"), std::string::npos) << twice;
  EXPECT_NE(twice.find("Rename the layers"), std::string::npos) << twice;
}

namespace {
// A layer's pieces, the largest `holed` of them with a hole (the faces within 4 mm of one vertex removed), each
// holed one with a fin as well when `fin` (a triangle on one of its edges: a non-manifold edge beside the hole)
void punch(OwnedMesh& m, std::size_t holed, bool fin) {
  Soup s = surfaceOf(m, kFiniteFaces);
  weld(s);
  auto pieces = components(s);
  std::sort(pieces.begin(), pieces.end(), [](const Soup& a, const Soup& b) { return volume(a) > volume(b); });
  Soup out;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    Soup p = pieces[i];
    if (i < holed) {
      const Eigen::Vector3d c = p.V[0];
      const auto far = [&](int v) { return (p.V[std::size_t(v)] - c).norm() > 4; };
      std::vector<std::array<int, 3>> kept;
      for (const auto& f : p.F)
        if (far(f[0]) && far(f[1]) && far(f[2])) kept.push_back(f);
      EXPECT_LT(kept.size(), p.F.size());
      p.F = std::move(kept);
      if (fin) {
        const auto f = p.F.back();
        p.V.push_back(p.V[std::size_t(f[0])] + Eigen::Vector3d(0, 0, 5));
        p.F.push_back({f[0], f[1], int(p.V.size()) - 1});
      }
    }
    append(out, p);
  }
  weld(out);
  m.Clear();
  toMesh(out, m);
}
// a structure's solid volume (cm3) and holes capped from the Log ("'name': 12 pieces -> a solid of 8.12 cm3 (3 holes
// capped)")
std::pair<double, int> solidOf(const PrepareResult& r, const std::string& name) {
  for (const auto& l : r.log)
    if (l.rfind("'" + name + "': ", 0) == 0 && l.find("a solid of ") != std::string::npos) {
      const double v = std::stod(l.substr(l.find("a solid of ") + 11));
      const auto open = l.find(" (", l.find("a solid of "));
      return {v, open == std::string::npos ? 0 : std::stoi(l.substr(open + 2))};
    }
  ADD_FAILURE() << "no solid of '" << name << "' in the Log";
  return {0, 0};
}
PrepareResult prepareHoled(std::size_t holed, bool fin, OwnedMesh& cage) {
  std::array<OwnedMesh, 3> m;
  toScanner(m);
  punch(m[1], holed, fin);
  PrepareOptions o;
  o.edgeLength = 3.0;
  return preparePatientCage(inputs(m), o, cage);
}
}  // namespace

// Cartilages with holes, with and without a fin beside each hole (a non-manifold edge): every hole is capped, and
// the solid holds what the whole cartilages hold, not a hollow shell (a cap is flat where the removed faces were
// curved: 8 mm holes in 10 mm bars take a few per cent).
TEST(PatientPrepare, HoledCartilageIsCappedSolid) {
  OwnedMesh clean, one, every;
  std::array<OwnedMesh, 3> m;
  toScanner(m);
  PrepareOptions o;
  o.edgeLength = 3.0;
  const auto [v0, caps0] = solidOf(preparePatientCage(inputs(m), o, clean), "costal cartilage");
  const auto [v1, caps1] = solidOf(prepareHoled(1, false, one), "costal cartilage");
  const auto [v2, caps2] = solidOf(prepareHoled(1000, true, every), "costal cartilage");
  std::printf("  costal cartilage: clean %.3f cm3, one hole %.3f cm3 (%d capped), every piece holed and finned %.3f cm3 "
              "(%d capped)\n", v0, v1, caps1, v2, caps2);
  EXPECT_EQ(caps0, 0);
  EXPECT_EQ(caps1, 1);
  EXPECT_GE(caps2, 10);
  EXPECT_NEAR(v1, v0, 0.01 * v0);
  EXPECT_NEAR(v2, v0, 0.08 * v0);
}

// A sternum split down its midline (the halves 30 mm apart, the faces across the midline removed) has no midline
// front surface: the deepest point of the funnel cannot be placed, and the message says to pick it. A picked
// point then stands for it.
TEST(PatientPrepare, RefusesALandmarkThatCannotBePlacedUnlessPicked) {
  const auto& e = exported();
  std::array<OwnedMesh, 3> m;
  for (int k = 0; k < 3; ++k) mapInto(e.layers[std::size_t(k)], m[std::size_t(k)], Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  for (auto& f : m[2].face)
    if (!f.IsD() && std::min({f.P(0)[0], f.P(1)[0], f.P(2)[0]}) < 0 && std::max({f.P(0)[0], f.P(1)[0], f.P(2)[0]}) >= 0)
      vcg::tri::Allocator<CMeshO>::DeleteFace(m[2], f);
  for (auto& v : m[2].vert) v.P()[0] += v.P()[0] >= 0 ? 15.0f : -15.0f;
  PrepareOptions o;
  o.edgeLength = 0;
  OwnedMesh cage;
  const std::string msg = errorOf([&] { preparePatientCage(inputs(m), o, cage); });
  EXPECT_NE(msg.find("Cannot place the landmark 'deepest point of the funnel' (code 501)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("Edit > PickPoints"), std::string::npos) << msg;
  EXPECT_NE(msg.find("the point named 501"), std::string::npos) << msg;

  const Landmark* deep = find(e.truth, kFunnelDeepest);
  ASSERT_TRUE(deep);
  o.userLandmarks = {{kFunnelDeepest, deep->p}};
  const auto r = preparePatientCage(inputs(m), o, cage);
  EXPECT_TRUE(logHas(r, "landmark 501 (deepest point of the funnel) cannot be placed automatically"));
  const Landmark* got = find(r.landmarks, kFunnelDeepest);
  ASSERT_TRUE(got);
  EXPECT_LT((got->p - (r.inputToModel * deep->p.homogeneous()).head<3>()).norm(), 1e-6);
}

// the options are checked against the ranges the filter declares (prepare.h) before any layer is read
TEST(PatientPrepare, OptionsOutsideTheirRangesAreRefused) {
  OwnedMesh cage;
  auto refused = [&](auto change, const std::string& words) {
    PrepareOptions o;
    change(o);
    EXPECT_NE(errorOf([&] { preparePatientCage({}, o, cage); }).find(words), std::string::npos) << words;
  };
  refused([](PrepareOptions& o) { o.minVolume = -1; }, "minimum volume must lie in [0, 100000] mm^3");
  refused([](PrepareOptions& o) { o.gridStep = kGridStepRange.lo / 2; }, "grid step must lie in [0.3, 3] mm");
  refused([](PrepareOptions& o) { o.edgeLength = kMinEdgeLength / 2; },
          "target edge length must be 0 or lie in [0.5, 10] mm");
}

namespace {
// a sphere of the given radius, an icosahedron subdivided `levels` times (edges about 2.6 mm at radius 10, 3 levels)
Soup ball(double radius, int levels) {
  OwnedMesh sphere;
  vcg::tri::Sphere(sphere, levels);
  for (auto& v : sphere.vert) v.P() *= radius;
  return surfaceOf(sphere, kFiniteFaces);
}
Soup ballOfRadius10() { return ball(10, 3); }

// the farthest distance at which the ray from the origin along the unit vector u crosses the surface s
double radiusAlong(const Soup& s, const Eigen::Vector3d& u) {
  double r = 0;
  for (const auto& f : s.F) {
    const Eigen::Vector3d a = s.V[std::size_t(f[0])], e1 = s.V[std::size_t(f[1])] - a, e2 = s.V[std::size_t(f[2])] - a;
    const Eigen::Vector3d p = u.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-15) continue;
    const double bu = -a.dot(p) / det, bv = u.dot((-a).cross(e1)) / det;
    if (bu >= 0 && bv >= 0 && bu + bv <= 1) r = std::max(r, e2.dot((-a).cross(e1)) / det);
  }
  return r;
}

// the ball with every 7th vertex moved most of the way to a neighbour: about 60 edges under 1.2 mm
Soup ballWithShortEdges() {
  Soup s = ballOfRadius10();
  std::vector<char> moved(s.V.size(), 0);
  for (const auto& f : s.F)
    if (f[0] % 7 == 0 && !moved[std::size_t(f[0])] && !moved[std::size_t(f[1])]) {
      s.V[std::size_t(f[0])] += 0.8 * (s.V[std::size_t(f[1])] - s.V[std::size_t(f[0])]);
      moved[std::size_t(f[0])] = 1;
    }
  return s;
}
}  // namespace

TEST(PatientSoup, ShortEdgesCollapsedKeepingTheSolid) {
  Soup s = ballWithShortEdges();
  auto edges = [](const Soup& x, double below) {
    int n = 0;
    for (const auto& f : x.F)
      for (int k = 0; k < 3; ++k) n += (x.V[std::size_t(f[k])] - x.V[std::size_t(f[(k + 1) % 3])]).norm() < below;
    return n / 2;
  };
  ASSERT_EQ(defects(s), "");
  const double v0 = volume(s), minLength = 1.2;
  const int shortBefore = edges(s, minLength);
  ASSERT_GT(shortBefore, 50);
  const int collapsed = collapseShortEdges(s, minLength);
  std::printf("  %d edges under %.1f mm, %d collapsed, %d left; volume %.1f -> %.1f mm3\n", shortBefore, minLength, collapsed,
              edges(s, minLength), v0, volume(s));
  EXPECT_GE(collapsed, shortBefore * 9 / 10);
  EXPECT_LE(edges(s, minLength), shortBefore / 20);
  EXPECT_EQ(defects(s), "");
  EXPECT_NEAR(volume(s), v0, 0.02 * v0);
  // an open soup is left as it was
  Soup open = s;
  open.F.pop_back();
  EXPECT_EQ(collapseShortEdges(open, 100.0), 0);
  EXPECT_EQ(open.F.size(), s.F.size() - 1);
}

TEST(PatientSoup, CollapseKeepsTheEdgesWhereItWouldCrossAnotherSurface) {
  // Collapsing the ball's short edges sinks its surface slightly where they were (chords of a sphere lie
  // inside it). A small icosahedral cavity whose top vertex lies halfway into that sinking is inside the ball
  // before the collapse and crosses its surface after it: the collapse is done again keeping the edges there.
  const Soup alone = ballWithShortEdges();
  Soup collapsedAlone = alone;
  ASSERT_GT(collapseShortEdges(collapsedAlone, 1.2), 0);
  Eigen::Vector3d deepest(0, 0, 1);
  double sink = 0, rBefore = 0;
  for (const auto& f : alone.F) {  // through the faces' centroids: rays through a vertex or an edge may slip between faces
    const Eigen::Vector3d u = (alone.V[std::size_t(f[0])] + alone.V[std::size_t(f[1])] + alone.V[std::size_t(f[2])]).normalized();
    const double r0 = radiusAlong(alone, u), r1 = radiusAlong(collapsedAlone, u);
    if (r1 > 0 && r0 - r1 > sink) sink = r0 - r1, deepest = u, rBefore = r0;
  }
  ASSERT_GT(sink, 1e-3);
  // the cavity: an icosahedron of circumradius 1.5 mm (edges 1.6 mm, none to collapse), a vertex towards the
  // surface, outward-facing triangles reversed so that it bounds a void
  Soup cavity = ball(1.5, 0);
  const Eigen::Quaterniond turn = Eigen::Quaterniond::FromTwoVectors(cavity.V[0].normalized(), deepest);
  const Eigen::Vector3d centre = (rBefore - 0.5 * sink - 1.5) * deepest;
  Soup s = alone;
  const int n = int(s.V.size());
  for (const auto& p : cavity.V) s.V.push_back(centre + turn * p);
  for (const auto& f : cavity.F) s.F.push_back({f[0] + n, f[2] + n, f[1] + n});
  ASSERT_EQ(defects(s), "");
  const std::size_t facesBefore = s.F.size();
  std::printf("  the collapse sinks the ball by up to %.4f mm\n", sink);
  int kept = 0;
  const int collapsed = collapseShortEdges(s, 1.2, &kept);
  std::printf("  %d edges collapsed, %d kept near the cavity\n", collapsed, kept);
  EXPECT_GT(kept, 0);
  EXPECT_GT(collapsed, 0);
  EXPECT_EQ(defects(s), "");
  EXPECT_LT(s.F.size(), facesBefore);  // the rest of the ball lost its short edges
}
