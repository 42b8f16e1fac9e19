// A real export's defects, reproduced by the CT phantom's messy export and counted in it, and that export
// prepared with the defaults: the whole cage, the same bytes on every run and thread count.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cstdio>

#include "pectus/patient/prepare.h"
#include "pectus/patient/soup.h"
#include "pectus/phantom/ct_phantom_core.h"
#include "pectus/self_intersections.h"

using namespace pectus;
using namespace pectus::patient;
using namespace pectus::phantom;

namespace {

// a 7-year-old's cage on a 1 mm CT grid, as the e2e tests and the docs use it
const Phantom& child() {
  static const Phantom ph = makePhantom(PhantomParams{});
  return ph;
}
const std::vector<ExportedFile>& exported() {
  static const std::vector<ExportedFile> files = messyExport(child(), 1);
  return files;
}
const ExportedFile& file(const std::string& name) {
  for (const auto& f : exported())
    if (f.name == name) return f;
  throw std::runtime_error("no file " + name);
}
Soup soupOf(const std::vector<Triangle>& tris) {
  Soup s;
  for (const auto& t : tris) {
    for (const auto& p : t) s.V.push_back(p);
    const int n = int(s.V.size());
    s.F.push_back({n - 3, n - 2, n - 1});
  }
  weld(s);
  return s;
}
double signedVolume(const Soup& s) {
  double v = 0;
  for (const auto& f : s.F) v += s.V[std::size_t(f[0])].dot(s.V[std::size_t(f[1])].cross(s.V[std::size_t(f[2])])) / 6;
  return v;
}
struct Pieces {
  std::size_t all = 0, specks = 0, inward = 0, twoFaces = 0, blocks = 0, large = 0;
};
Pieces piecesOf(Soup s) {
  removeDuplicateFaces(s);  // a face written twice would add its cone's volume
  Pieces p;
  for (const auto& c : components(s)) {
    ++p.all;
    const double v = signedVolume(c);
    p.specks += c.F.size() > 2 && v > 0 && v < 1.0;
    p.inward += v < -1.0;          // a closed shell facing inward: a cavity's boundary
    p.twoFaces += c.F.size() == 2;  // a sliver
    p.blocks += v > 200 && v < 600;
    p.large += v > 1000;
  }
  return p;
}
// faces lying flat in the plane z = the surface's top (or bottom) in the scanner frame
std::size_t flatAt(const Soup& s, bool top) {
  double z = top ? -1e300 : 1e300;
  for (const auto& q : s.V) z = top ? std::max(z, q.z()) : std::min(z, q.z());
  return std::size_t(std::count_if(s.F.begin(), s.F.end(), [&](const auto& f) {
    return std::all_of(f.begin(), f.end(), [&](int v) { return std::abs(s.V[std::size_t(v)].z() - z) < 1e-6; });
  }));
}
std::size_t duplicates(const Soup& s) {
  Soup d = s;
  return std::size_t(removeDuplicateFaces(d));
}

}  // namespace

// Each defect of the real export in patient-data.md, counted in the phantom's messy export.
TEST(PatientExport, TheMessyExportHasTheDefectsOfARealOne) {
  const Soup bone = soupOf(file("bone").tris), sternum = soupOf(file("sternum").tris), cart = soupOf(file("costal_cartilages").tris);
  const Pieces b = piecesOf(bone), st = piecesOf(sternum), c = piecesOf(cart);
  const std::size_t top = flatAt(bone, true), bottom = flatAt(bone, false);
  const Topology tc(cart);
  const auto crossing = selfIntersections(sternum.V, sternum.F);
  std::printf("  bone: %zu faces, %zu pieces, %zu specks under 1 mm3, %zu marrow shells, %zu blocks of 200-600 mm3, %zu faces "
              "written twice, %zu and %zu faces flat on the top and bottom cuts\n",
              bone.F.size(), b.all, b.specks, b.inward, b.blocks, duplicates(bone), top, bottom);
  std::printf("  sternum: %zu pieces (%zu over 1 cm3, %zu cavities, %zu two-face slivers), %zu self-intersecting face pairs\n",
              st.all, st.large, st.inward, st.twoFaces, crossing.size());
  std::printf("  costal cartilages: %zu pieces, %zu open edges\n", c.all, tc.edgeUse().once);
  EXPECT_GE(b.specks, 900u);
  EXPECT_GE(b.inward, 24u + 12u);  // a marrow shell in each rib and vertebra
  EXPECT_EQ(b.blocks, 2u);
  EXPECT_EQ(duplicates(bone), 619u);
  EXPECT_GT(top, 50u);
  EXPECT_GT(bottom, 5u);
  EXPECT_GE(st.all, 15u);
  EXPECT_GE(st.large, 2u);  // manubrium and body apart
  EXPECT_GE(st.inward, 2u);
  EXPECT_EQ(st.twoFaces, 10u);
  EXPECT_GT(crossing.size(), 10u);
  EXPECT_GE(c.all, 12u);
  EXPECT_GT(tc.edgeUse().once, 9u);
}

// The messy export, prepared with the defaults: 12 ribs a side, every landmark, and the same cage (vertices, faces,
// labels, landmarks) bit for bit with one thread and with two.
TEST(PatientExport, PreparedWithTheDefaultsTheSameEveryRun) {
  std::vector<std::unique_ptr<OwnedMesh>> meshes;
  std::vector<InputLayer> layers;
  for (const auto& f : exported()) {
    meshes.push_back(std::make_unique<OwnedMesh>());
    toMesh(soupOf(f.tris), *meshes.back());
    layers.push_back({f.name, meshes.back().get()});
  }
  OwnedMesh a, b;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto ra = preparePatientCage(layers, PrepareOptions{}, a);
  omp_set_num_threads(std::max(2, threads));
  const auto rb = preparePatientCage(layers, PrepareOptions{}, b);
  omp_set_num_threads(threads);
  for (const auto& l : ra.log) std::printf("  %s\n", l.c_str());
  EXPECT_EQ(ra.ribsRight, 12);
  EXPECT_EQ(ra.ribsLeft, 12);
  EXPECT_EQ(ra.landmarks.size(), 48u);
  const Soup sa = surfaceOf(a, kFiniteFaces), sb = surfaceOf(b, kFiniteFaces);
  ASSERT_EQ(sa.V.size(), sb.V.size());
  ASSERT_EQ(sa.F, sb.F);
  EXPECT_TRUE(std::equal(sa.V.begin(), sa.V.end(), sb.V.begin()));
  const auto la = readFaceLabels(a), lb = readFaceLabels(b);
  ASSERT_TRUE(la && lb);
  EXPECT_EQ(la->tissue, lb->tissue);
  EXPECT_EQ(la->part, lb->part);
  ASSERT_EQ(ra.landmarks.size(), rb.landmarks.size());
  for (std::size_t i = 0; i < ra.landmarks.size(); ++i) EXPECT_EQ(ra.landmarks[i].p, rb.landmarks[i].p) << ra.landmarks[i].code;
  EXPECT_EQ(defects(sa), "");
}
