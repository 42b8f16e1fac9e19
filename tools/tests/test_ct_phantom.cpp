// The CT phantom's label map on a small coarse cage: every structure present, ribs in one piece,
// vertebrae touching their ribs, scapulae clear of the ribs, stray voxels isolated, determinism.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "pectus/phantom/ct_phantom_core.h"

using namespace pectus;
using namespace pectus::phantom;

namespace {

const Phantom& coarse() {
  static const Phantom ph = [] {
    PhantomParams p;
    p.cage.age = 5;
    p.cage.edgeLength = 2.0;
    p.spacing = Eigen::Vector3d(2.0, 2.0, 2.0);
    p.seed = 7;
    return makePhantom(p);
  }();
  return ph;
}

std::size_t idx(const patient::LabelVolume& v, int i, int j, int k) {
  return std::size_t(i) + std::size_t(v.dims[0]) * (std::size_t(j) + std::size_t(v.dims[1]) * std::size_t(k));
}

// face-connected (6-neighbour) components of one label, stray voxels left out
int components(const patient::LabelVolume& v, int label, const std::set<std::size_t>& skip) {
  std::vector<char> seen(v.labels.size(), 0);
  int n = 0;
  for (std::size_t s = 0; s < v.labels.size(); ++s) {
    if (v.labels[s] != label || seen[s] || skip.count(s)) continue;
    ++n;
    std::vector<std::size_t> stack{s};
    seen[s] = 1;
    while (!stack.empty()) {
      const std::size_t q = stack.back();
      stack.pop_back();
      const int i = int(q % std::size_t(v.dims[0])), j = int((q / std::size_t(v.dims[0])) % std::size_t(v.dims[1])),
                k = int(q / (std::size_t(v.dims[0]) * std::size_t(v.dims[1])));
      const int d[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
      for (const auto& o : d) {
        const int a = i + o[0], b = j + o[1], c = k + o[2];
        if (a < 0 || b < 0 || c < 0 || a >= v.dims[0] || b >= v.dims[1] || c >= v.dims[2]) continue;
        const std::size_t r = idx(v, a, b, c);
        if (v.labels[r] == label && !seen[r] && !skip.count(r)) { seen[r] = 1; stack.push_back(r); }
      }
    }
  }
  return n;
}

// pairs of labels with voxels adjacent through a face (six) or through a face, edge or corner (all 26)
std::set<std::pair<int, int>> contacts(const patient::LabelVolume& v, bool all26) {
  std::set<std::pair<int, int>> out;
  for (int k = 0; k < v.dims[2]; ++k)
    for (int j = 0; j < v.dims[1]; ++j)
      for (int i = 0; i < v.dims[0]; ++i) {
        const int a = v.at(i, j, k);
        if (!a) continue;
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              if (!all26 && std::abs(di) + std::abs(dj) + std::abs(dk) != 1) continue;
              const int x = i + di, y = j + dj, z = k + dk;
              if (x < 0 || y < 0 || z < 0 || x >= v.dims[0] || y >= v.dims[1] || z >= v.dims[2]) continue;
              const int b = v.at(x, y, z);
              if (b && b != a) out.insert({a, b});
            }
      }
  return out;
}

}  // namespace

TEST(CtPhantom, EveryStructureIsPresent) {
  const Phantom& ph = coarse();
  const auto present = ph.volume.presentLabels();
  std::set<std::string> names;
  for (int l : present) {
    ASSERT_TRUE(ph.volume.names.count(l)) << "label " << l << " has no name";
    names.insert(ph.volume.names.at(l));
  }
  for (int k = 1; k <= 12; ++k) {
    EXPECT_TRUE(names.count("rib_left_" + std::to_string(k))) << k;
    EXPECT_TRUE(names.count("rib_right_" + std::to_string(k))) << k;
    EXPECT_TRUE(names.count("vertebrae_T" + std::to_string(k))) << k;
  }
  for (const char* n : {"costal_cartilages", "sternum", "scapula_left", "scapula_right"}) EXPECT_TRUE(names.count(n)) << n;
  EXPECT_EQ(present.size(), 24u + 12u + 4u);
  EXPECT_EQ(ph.strays.size(), 3u);
  EXPECT_EQ(ph.volume.names.at(ribLabel(2, 5)), "rib_left_5");
  EXPECT_EQ(ph.volume.names.at(vertebraLabel(12)), "vertebrae_T12");
}

TEST(CtPhantom, RibsAreOnePieceApartFromStrayVoxels) {
  const Phantom& ph = coarse();
  std::set<std::size_t> strays;
  for (const auto& s : ph.strays) strays.insert(idx(ph.volume, s[0], s[1], s[2]));
  for (int side = 1; side <= 2; ++side)
    for (int k = 1; k <= 12; ++k) EXPECT_EQ(components(ph.volume, ribLabel(side, k), strays), 1) << "side " << side << " rib " << k;
  // each stray voxel has no labelled voxel within 10 mm but itself
  const auto& v = ph.volume;
  for (const auto& s : ph.strays) {
    EXPECT_EQ(v.at(s[0], s[1], s[2]), ph.strayLabel);
    for (int dk = -5; dk <= 5; ++dk)
      for (int dj = -5; dj <= 5; ++dj)
        for (int di = -5; di <= 5; ++di) {
          if (!di && !dj && !dk) continue;
          if ((di * di + dj * dj + dk * dk) * 4 >= 100) continue;
          const int i = s[0] + di, j = s[1] + dj, k = s[2] + dk;
          if (i < 0 || j < 0 || k < 0 || i >= v.dims[0] || j >= v.dims[1] || k >= v.dims[2]) continue;
          EXPECT_EQ(v.at(i, j, k), 0);
        }
  }
}

TEST(CtPhantom, VertebraeTouchTheirRibsAndScapulaeDoNot) {
  const Phantom& ph = coarse();
  const auto face = contacts(ph.volume, false);
  for (int k = 1; k <= 12; ++k)
    for (int side = 1; side <= 2; ++side)
      EXPECT_TRUE(face.count({vertebraLabel(k), ribLabel(side, k)})) << "T" << k << " and rib " << k << " side " << side;
  // consecutive vertebrae are apart (disc gap)
  const auto all = contacts(ph.volume, true);
  for (int k = 1; k < 12; ++k) EXPECT_FALSE(all.count({vertebraLabel(k), vertebraLabel(k + 1)})) << k;
  for (const auto& [a, b] : all)
    if (a == kScapulaLeftLabel || a == kScapulaRightLabel) ADD_FAILURE() << "scapula " << a << " touches label " << b;
}

TEST(CtPhantom, LandmarksAreInTheScannerFrame) {
  const Phantom& ph = coarse();
  // RAS: the left costovertebral joint (code 201) has a smaller x than the right one (101)
  Eigen::Vector3d l = Eigen::Vector3d::Zero(), r = Eigen::Vector3d::Zero();
  for (const auto& m : ph.landmarks) {
    if (m.code == 201) l = m.p;
    if (m.code == 101) r = m.p;
  }
  EXPECT_LT(l.x(), r.x());
  EXPECT_NEAR(0.5 * (l.x() + r.x()), -120.0, 1e-6);
  // the landmark lies in the grid: inverse affine gives an index inside the volume
  const Eigen::Vector4d ijk = ph.volume.voxelToMm.inverse() * Eigen::Vector4d(l.x(), l.y(), l.z(), 1);
  for (int a = 0; a < 3; ++a) {
    EXPECT_GT(ijk[a], 0);
    EXPECT_LT(ijk[a], ph.volume.dims[std::size_t(a)] - 1);
  }
}
