// The vertebral column of a fused-bone export (ribs and vertebrae in one 'bone' layer, as the CT phantom's
// messy STL export writes it), cut away at the costovertebral joints or kept as the fixed support: the kept
// column is part 400 of a closed, manifold cage, the landmarks do not change, the FE analysis holds every
// node of the column and the sternum moves about as much as with the column cut, and the thoracic volume
// leaves the column out.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "pectus/phantom/ct_phantom_core.h"
#include "pectus/patient/label_volume.h"
#include "pectus/nuss/nuss_analysis.h"
#include "pectus/errors.h"
#include "pectus/vol/thoracic_volume.h"
#include "pectus/patient/prepare.h"
#include "pectus/patient/soup.h"

using namespace pectus;
using namespace pectus::patient;

namespace {

struct Prepared {
  OwnedMesh cage;
  PrepareResult r;
};
struct Fused {
  std::array<OwnedMesh, 3> layers;  // bone (ribs fused to T1-T12), costal cartilages, sternum
  Prepared cut, keep;
};

// the phantom's label map (the default cage on 2 mm voxels, RAS) as three surfaces, then prepared both ways
// (4 mm edges: a coarse model, quick to prepare and to solve)
const Fused& fused() {
  static Fused f;
  static const bool made = [] {
    phantom::PhantomParams p;
    p.spacing = Eigen::Vector3d(2.0, 2.0, 2.0);
    const phantom::Phantom ph = phantom::makePhantom(p);
    const LabelVolume& v = ph.volume;
    std::set<int> bone;
    for (const auto& [l, name] : v.names)
      if (name.rfind("rib_", 0) == 0 || name.rfind("vertebrae_", 0) == 0) bone.insert(l);
    LabelVolume b = v;
    for (auto& l : b.labels) l = bone.count(l) ? 1 : 0;
    extractLabelSurface(b, 1, f.layers[0]);
    extractLabelSurface(v, phantom::kCartilageLabel, f.layers[1]);
    extractLabelSurface(v, phantom::kSternumLabel, f.layers[2]);
    const std::vector<InputLayer> in{{"bone", &f.layers[0]}, {"costal_cartilages", &f.layers[1]}, {"sternum", &f.layers[2]}};
    PrepareOptions o;
    o.edgeLength = 4.0;
    for (auto* pr : {&f.cut, &f.keep}) {
      o.spine = pr == &f.cut ? SpineMode::Cut : SpineMode::Keep;
      try {
        pr->r = preparePatientCage(in, o, pr->cage);
      } catch (const InputError& e) {
        ADD_FAILURE() << (pr == &f.cut ? "cut: " : "keep: ") << e.what();
        throw;
      }
    }
    for (const auto* pr : {&f.cut, &f.keep}) {
      std::printf("--- %s (%.1f s)\n", pr == &f.cut ? "cut" : "keep", pr->r.seconds);
      for (const auto& l : pr->r.log) std::printf("  %s\n", l.c_str());
    }
    return true;
  }();
  (void)made;
  return f;
}

int facesOfPart(const CMeshO& m, int part, int tissue) {
  const auto lab = readFaceLabels(m);
  int n = 0;
  for (std::size_t f = 0; f < m.face.size(); ++f)
    if (!m.face[f].IsD() && lab->part[f] == part && lab->tissue[f] == tissue) ++n;
  return n;
}

const Landmark* find(const std::vector<Landmark>& l, int code) {
  for (const auto& x : l)
    if (x.code == code) return &x;
  return nullptr;
}

nuss::Options smallStrainTet4() {
  nuss::Options o;
  o.mesh.order = 1;
  o.nonlinear = false;
  o.force = 100;
  return o;
}

// One test: preparing the phantom both ways takes a minute or two, and ctest runs every TEST in a process of
// its own. The parts: the cage, the FE analysis, the thoracic volume.
void keptColumnIsPart400OfAClosedManifoldCage() {
  const auto& f = fused();
  EXPECT_EQ(f.cut.r.ribsRight, 12);
  EXPECT_EQ(f.keep.r.ribsRight, 12);
  EXPECT_EQ(f.keep.r.ribsLeft, 12);
  ASSERT_TRUE(readFaceLabels(f.keep.cage) && readFaceLabels(f.cut.cage));
  EXPECT_EQ(facesOfPart(f.cut.cage, kVertebralColumn, int(Tissue::Bone)), 0);
  const int column = facesOfPart(f.keep.cage, kVertebralColumn, int(Tissue::Bone));
  std::printf("faces: cut %d, keep %d (%d of the column)\n", f.cut.cage.fn, f.keep.cage.fn, column);
  EXPECT_GT(column, 1000);
  // the column lies on the posterior midline, behind the cage's joints
  const auto lab = readFaceLabels(f.keep.cage);
  for (std::size_t i = 0; i < f.keep.cage.face.size(); ++i)
    if (lab->part[i] == kVertebralColumn) {
      const auto c = toEigen((f.keep.cage.face[i].cP(0) + f.keep.cage.face[i].cP(1) + f.keep.cage.face[i].cP(2)) / 3.0f);
      EXPECT_LT(std::abs(c.x()), 30.0) << "column face off the midline at x " << c.x();
      EXPECT_LT(c.y(), 15.0) << "column face in front of the spine at y " << c.y();
    }
  // closed, 2-manifold, not self-intersecting: what the FE analysis' TetGen needs
  EXPECT_EQ(defects(surfaceOf(f.keep.cage, kFiniteFaces)), "");
  EXPECT_EQ(defects(surfaceOf(f.cut.cage, kFiniteFaces)), "");
  EXPECT_TRUE(std::any_of(f.keep.r.log.begin(), f.keep.r.log.end(),
                          [](const std::string& l) { return l.find("kept as the fixed support") != std::string::npos; }));
  // the same landmarks either way (with the column kept they are placed on the cage joined without it)
  ASSERT_EQ(f.keep.r.landmarks.size(), f.cut.r.landmarks.size());
  double worst = 0;
  int worstCode = 0;
  for (const auto& l : f.cut.r.landmarks) {
    const Landmark* k = find(f.keep.r.landmarks, l.code);
    ASSERT_TRUE(k) << "landmark " << l.code << " missing with the column kept";
    const double d = (k->p - l.p).norm();
    if (d > worst) worst = d, worstCode = l.code;
    EXPECT_LT(d, 1e-3) << "landmark " << l.code;
  }
  std::printf("landmarks: largest difference keep - cut %.2f mm (code %d)\n", worst, worstCode);
}

// TET4, small strain, a given force: the column's nodes are all fixed and the sternum rises about as much as
// with the column cut away (the column is a rigid support where the cut model is held at the joints).
void feHoldsTheColumnAndMovesTheSternumAsWithoutIt() {
  const auto& f = fused();
  const auto o = smallStrainTet4();
  const auto sCut = nuss::cageFromMesh(f.cut.cage);
  const auto sKeep = nuss::cageFromMesh(f.keep.cage);
  const nuss::Analysis a = nuss::analyze(sCut, f.cut.r.landmarks, o);
  const nuss::Analysis b = nuss::analyze(sKeep, f.keep.r.landmarks, o);
  EXPECT_EQ(a.fixedOnColumn, 0);
  EXPECT_GT(b.fixedOnColumn, 500);
  EXPECT_EQ(int(b.fixedNodes.size()), b.fixedAtJoints + b.fixedOnColumn);
  std::set<int> fixed(b.fixedNodes.begin(), b.fixedNodes.end());
  int columnTets = 0;
  for (int t = 0; t < b.mesh.numTets(); ++t)
    if (b.tetPart[std::size_t(t)] == kVertebralColumn) {
      ++columnTets;
      for (int k = 0; k < b.mesh.nodesPerTet(); ++k) ASSERT_TRUE(fixed.count(b.mesh.tets[std::size_t(t)][std::size_t(k)]));
    }
  EXPECT_GT(columnTets, 500);
  for (int n : b.fixedNodes) ASSERT_EQ(b.result.displacement(n).norm(), 0.0);
  std::printf("cut:  %d tets, %zu fixed nodes, elevation %.3f mm at %.0f N, max strain %.4f in the %s\n", a.mesh.numTets(),
              a.fixedNodes.size(), a.elevation, a.force, a.maxStrain, a.maxStrainAt.describe().c_str());
  std::printf("keep: %d tets (%d of the column), %d fixed at the joints + %d on the column, elevation %.3f mm, max strain "
              "%.4f in the %s\n",
              b.mesh.numTets(), columnTets, b.fixedAtJoints, b.fixedOnColumn, b.elevation, b.maxStrain, b.maxStrainAt.describe().c_str());
  const double rel = (b.elevation - a.elevation) / a.elevation;
  std::printf("elevation keep vs cut: %+.2f %%\n", 100 * rel);
  // The column is a rigid support where the cut model is held at the joints: close results, up to the
  // discretisation. The two cages are decimated separately (the kept one has the column's area too), so their
  // cartilages are meshed differently, and TET4 at 4 mm edges (1-2 elements across a cartilage) is
  // mesh-sensitive: measured at 100 N, cut 331 mm at 4.0 mm edges, 372 mm at 3.7 mm (+12 %) and 417 mm at
  // 4.3 mm (+26 %); kept, 375-381 mm at 4.0 mm (+13-15 %: the decimation is not quite the same from run to
  // run of the preparation).
  EXPECT_GT(b.elevation, 0.0);
  EXPECT_LT(std::abs(rel), 0.25);
}

// The thoracic volume leaves the column's faces out: the same volume whether it was kept or cut away.
void thoracicVolumeLeavesTheColumnOut() {
  const auto& f = fused();
  const Landmark* dome = find(f.cut.r.landmarks, kDiaphragmDome);
  const Landmark* apex = find(f.cut.r.landmarks, kLungApex);
  ASSERT_TRUE(dome && apex);
  const vol::Range range{dome->p.z(), apex->p.z()};
  const vol::Soup cut = vol::soupFromMesh(f.cut.cage, "cut");
  const vol::Soup keep = vol::soupFromMesh(f.keep.cage, "keep");
  EXPECT_EQ(int(keep.F.size()), f.keep.cage.fn - facesOfPart(f.keep.cage, kVertebralColumn, int(Tissue::Bone)));
  const double vCut = vol::sliceVolume(cut, range, {}).volume;
  const double vKeep = vol::sliceVolume(keep, range, {}).volume;
  // with its faces, the column's front would bound the slices instead of the gap between the rib heads
  vol::Soup all = keep;
  all.F.clear();
  for (const auto& fc : f.keep.cage.face)
    if (!fc.IsD()) all.F.push_back({int(vcg::tri::Index(f.keep.cage, fc.cV(0))), int(vcg::tri::Index(f.keep.cage, fc.cV(1))),
                                    int(vcg::tri::Index(f.keep.cage, fc.cV(2)))});
  const double vAll = vol::sliceVolume(all, range, {}).volume;
  const double eCut = vol::fergusonEnvelope(cut, range, {}).volume, eKeep = vol::fergusonEnvelope(keep, range, {}).volume;
  std::printf("slice volume: cut %.1f cm3, keep %.1f cm3 (%.1f cm3 with the column's faces); envelope: cut %.1f, keep %.1f cm3\n",
              vCut / 1000, vKeep / 1000, vAll / 1000, eCut / 1000, eKeep / 1000);
  // The two cages are joined and decimated each on its own (the rib heads meet the vertebrae only where the
  // column is kept), and the preparation is not repeatable from run to run (docs/robustness.md), so their
  // volumes differ by the preparation: slice method 0.8-1.6 %, envelope 0.2-3.7 % on the default phantom
  // across runs and the hosts' vcglib (docs/hosts.md). The column's faces, left in, would take 11-14 % of the
  // slice volume away: the test tells the two apart by more than a factor of 4.
  constexpr double kPreparation = 0.02, kPreparationEnvelope = 0.05;
  EXPECT_NEAR(vKeep, vCut, kPreparation * vCut);
  EXPECT_NEAR(eKeep, eCut, kPreparationEnvelope * eCut);
  EXPECT_GT(std::abs(vAll - vCut), 4 * kPreparation * vCut);
}

}  // namespace

TEST(PatientSpine, CutOrKeptAsTheFixedSupport) {
  {
    SCOPED_TRACE("the prepared cages");
    keptColumnIsPart400OfAClosedManifoldCage();
  }
  if (HasFatalFailure()) return;
  {
    SCOPED_TRACE("the FE analysis");
    feHoldsTheColumnAndMovesTheSternumAsWithoutIt();
  }
  {
    SCOPED_TRACE("the thoracic volume");
    thoracicVolumeLeavesTheColumnOut();
  }
}
