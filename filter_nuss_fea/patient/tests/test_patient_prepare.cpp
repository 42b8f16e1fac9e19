// The preparation of a patient's rib cage, on the generator's own cage exported one layer per tissue
// (as segmentation tools export them), moved into a scanner frame: the prepared cage must come back
// numbered, labelled and landmarked like the generator's.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "pectus/errors.h"
#include "prepare.h"
#include "ribcage.h"

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
  expectError({{"Segment_1", &m[0]}, {"Segment_2", &m[1]}}, "None of the 2 layers");
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
